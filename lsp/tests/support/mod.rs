//! A scripted client talking to the server in process (`Connection::memory`),
//! shared by the test crates (each uses part of it).
#![allow(dead_code)]

use leeway_lsp::server::serve;
use lsp_server::{Connection, Message, Notification, Request, RequestId};
use serde_json::{Value, json};
use std::thread::JoinHandle;
use std::time::Duration;

/// Guards against a hang only (a test that waits this long has failed).
const PATIENCE: Duration = Duration::from_secs(120);

pub struct Client {
    conn: Connection,
    server: Option<JoinHandle<bool>>,
    next_id: i32,
    /// Notifications received while waiting for responses.
    pub published: Vec<Value>,
}

pub const URI: &str = "file:///model.som";

impl Client {
    pub fn start() -> Client {
        let (server, conn) = Connection::memory();
        let handle = std::thread::spawn(move || serve(&server).is_ok());
        let mut c = Client {
            conn,
            server: Some(handle),
            next_id: 0,
            published: Vec::new(),
        };
        let caps = c.request("initialize", json!({"capabilities": {}}));
        assert!(
            caps["capabilities"]["hoverProvider"]
                .as_bool()
                .unwrap_or(false)
        );
        c.notify("initialized", json!({}));
        c
    }

    pub fn notify(&mut self, method: &str, params: Value) {
        let n = Notification::new(method.to_string(), params);
        self.conn
            .sender
            .send(Message::Notification(n))
            .expect("server alive");
    }

    /// Sends a request, returns its result (`Err` with the error's message).
    pub fn try_request(&mut self, method: &str, params: Value) -> Result<Value, String> {
        self.next_id += 1;
        let id = RequestId::from(self.next_id);
        let req = Request::new(id.clone(), method.to_string(), params);
        self.conn
            .sender
            .send(Message::Request(req))
            .expect("server alive");
        loop {
            match self
                .conn
                .receiver
                .recv_timeout(PATIENCE)
                .expect("an answer")
            {
                Message::Response(r) if r.id == id => {
                    return match r.error {
                        Some(e) => Err(e.message),
                        None => Ok(r.result.unwrap_or(Value::Null)),
                    };
                }
                Message::Notification(n) => self.published.push(n.params),
                _ => {}
            }
        }
    }

    pub fn request(&mut self, method: &str, params: Value) -> Value {
        self.try_request(method, params)
            .unwrap_or_else(|e| panic!("{method}: {e}"))
    }

    /// The diagnostics published for `version` (waits for them).
    pub fn diagnostics(&mut self, version: i32) -> Vec<Value> {
        loop {
            if let Some(i) = self
                .published
                .iter()
                .position(|p| p["version"] == json!(version))
            {
                let p = self.published.remove(i);
                return p["diagnostics"].as_array().cloned().unwrap_or_default();
            }
            match self
                .conn
                .receiver
                .recv_timeout(PATIENCE)
                .expect("diagnostics")
            {
                Message::Notification(n) if n.method == "textDocument/publishDiagnostics" => {
                    self.published.push(n.params)
                }
                _ => {}
            }
        }
    }

    pub fn open(&mut self, text: &str) {
        self.notify(
            "textDocument/didOpen",
            json!({"textDocument": {"uri": URI, "languageId": "som", "version": 1, "text": text}}),
        );
    }

    pub fn at(&self, line: u32, character: u32) -> Value {
        json!({"textDocument": {"uri": URI}, "position": {"line": line, "character": character}})
    }

    /// `shutdown` and `exit`; the server's loop ends cleanly.
    pub fn stop(mut self) {
        assert_eq!(self.request("shutdown", Value::Null), Value::Null);
        self.notify("exit", Value::Null);
        let ended = self.server.take().map(|h| h.join().expect("no panic"));
        assert_eq!(ended, Some(true));
    }

    /// Whether the server thread is still running (it has not panicked).
    pub fn alive(&self) -> bool {
        self.server.as_ref().is_some_and(|h| !h.is_finished())
    }
}

/// The protocol position of byte `offset`, counted here independently of
/// the server: lines, then UTF-16 code units.
pub fn utf16_position(text: &str, offset: usize) -> (u32, u32) {
    let before = &text[..offset];
    let line = before.matches('\n').count();
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        line as u32,
        text[start..offset].encode_utf16().count() as u32,
    )
}
