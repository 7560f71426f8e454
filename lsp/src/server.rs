//! The server's loop over one connection: the documents, the requests in
//! the order they came (one thread: an edit is never reordered past a
//! request), and the diagnostics published once the queue is drained (a
//! burst of keystrokes is analysed once, for its last version).

use crate::analysis::Analysis;
use crate::last::{LastParsed, Unchanged};
use crate::symbols::Kind;
use crate::{actions, diagnostics, hover, text, tokens};
use leeway_grammar::Span;
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, Notification as _,
    PublishDiagnostics,
};
use lsp_types::request::{
    CodeActionRequest, Completion, DocumentSymbolRequest, Formatting, GotoDefinition, HoverRequest,
    References, Request as _, SemanticTokensFullRequest,
};
use lsp_types::{
    CompletionItem, CompletionItemKind, CompletionResponse, DocumentSymbol, DocumentSymbolResponse,
    GotoDefinitionResponse, Hover, HoverContents, HoverProviderCapability, Location, MarkupContent,
    MarkupKind, OneOf, PublishDiagnosticsParams, ServerCapabilities, SymbolKind,
    TextDocumentPositionParams, TextDocumentSyncCapability, TextDocumentSyncKind, TextEdit, Uri,
};
use std::collections::{BTreeSet, HashMap};

/// The keywords offered by completion.
const KEYWORDS: &[&str] = &[
    "model",
    "step",
    "state",
    "input",
    "heading",
    "integrates",
    "axes",
    "rotation",
    "disturbance",
    "unmeasured",
    "measured",
    "earth",
    "body",
    "relative",
    "der",
    "next",
    "nominal",
    "data",
    "delay",
    "steps",
    "in",
];

/// What the server offers, sent in answer to `initialize`.
pub fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        text_document_sync: Some(TextDocumentSyncCapability::Kind(
            TextDocumentSyncKind::INCREMENTAL,
        )),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        definition_provider: Some(OneOf::Left(true)),
        references_provider: Some(OneOf::Left(true)),
        document_symbol_provider: Some(OneOf::Left(true)),
        document_formatting_provider: Some(OneOf::Left(true)),
        code_action_provider: Some(lsp_types::CodeActionProviderCapability::Simple(true)),
        semantic_tokens_provider: Some(
            lsp_types::SemanticTokensOptions {
                legend: tokens::legend(),
                full: Some(lsp_types::SemanticTokensFullOptions::Bool(true)),
                ..Default::default()
            }
            .into(),
        ),
        completion_provider: Some(lsp_types::CompletionOptions {
            trigger_characters: Some(vec![".".into()]),
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// The open documents by URI (as text: `Uri` caches its parse inside).
type Docs = HashMap<String, Document>;

struct Document {
    uri: Uri,
    text: String,
    version: i32,
    analysis: Option<Analysis>,
    /// The last analysed version that parsed, while the text does not.
    last_parsed: Option<LastParsed>,
}

impl Document {
    fn analysis(&mut self) -> &Analysis {
        self.analysis
            .get_or_insert_with(|| Analysis::of(&self.text))
    }
}

/// The error that ends the loop: the connection is gone.
#[derive(Debug)]
pub struct Disconnected;

/// Serves one client on `connection` until `shutdown` and `exit` (or until
/// the client goes away). The `initialize` handshake is done here.
pub fn serve(connection: &Connection) -> Result<(), Disconnected> {
    let caps = serde_json::to_value(capabilities()).map_err(|_| Disconnected)?;
    connection.initialize(caps).map_err(|_| Disconnected)?;
    let mut docs: Docs = HashMap::new();
    let mut dirty: BTreeSet<String> = BTreeSet::new();
    loop {
        let Ok(first) = connection.receiver.recv() else {
            return Ok(());
        };
        let mut next = Some(first);
        while let Some(message) = next.take() {
            match message {
                Message::Request(req) => {
                    if connection.handle_shutdown(&req).map_err(|_| Disconnected)? {
                        return Ok(());
                    }
                    let response = answer(&mut docs, req);
                    connection
                        .sender
                        .send(Message::Response(response))
                        .map_err(|_| Disconnected)?;
                }
                Message::Notification(n) => {
                    if let Some(closed) = notify(&mut docs, &mut dirty, n) {
                        // A closed file's diagnostics leave the editor's list.
                        let params = PublishDiagnosticsParams::new(closed, Vec::new(), None);
                        send_notification::<PublishDiagnostics>(connection, params)?;
                    }
                }
                Message::Response(_) => {}
            }
            next = connection.receiver.try_recv().ok();
        }
        // The queue is empty: publish what the edits changed.
        for key in std::mem::take(&mut dirty) {
            let Some(doc) = docs.get_mut(&key) else {
                continue;
            };
            let analysis = doc.analysis.get_or_insert_with(|| Analysis::of(&doc.text));
            let params = PublishDiagnosticsParams {
                uri: doc.uri.clone(),
                diagnostics: diagnostics::of(&doc.uri, &doc.text, analysis),
                version: Some(doc.version),
            };
            send_notification::<PublishDiagnostics>(connection, params)?;
        }
    }
}

fn send_notification<N: lsp_types::notification::Notification>(
    connection: &Connection,
    params: N::Params,
) -> Result<(), Disconnected> {
    let n = Notification::new(N::METHOD.to_string(), params);
    connection
        .sender
        .send(Message::Notification(n))
        .map_err(|_| Disconnected)
}

/// Applies a notification; returns the URI of a document it closed.
fn notify(docs: &mut Docs, dirty: &mut BTreeSet<String>, n: Notification) -> Option<Uri> {
    match n.method.as_str() {
        DidOpenTextDocument::METHOD => {
            if let Ok(p) = serde_json::from_value::<lsp_types::DidOpenTextDocumentParams>(n.params)
            {
                let key = p.text_document.uri.as_str().to_string();
                dirty.insert(key.clone());
                docs.insert(
                    key,
                    Document {
                        uri: p.text_document.uri,
                        text: p.text_document.text,
                        version: p.text_document.version,
                        analysis: None,
                        last_parsed: None,
                    },
                );
            }
        }
        DidChangeTextDocument::METHOD => {
            if let Ok(p) =
                serde_json::from_value::<lsp_types::DidChangeTextDocumentParams>(n.params)
                && let Some(doc) = docs.get_mut(p.text_document.uri.as_str())
            {
                if let Some(analysis) = doc.analysis.take()
                    && analysis.model.is_some()
                {
                    doc.last_parsed = Some(LastParsed {
                        text: doc.text.clone(),
                        analysis,
                    });
                }
                for change in p.content_changes {
                    text::apply(&mut doc.text, change.range, &change.text);
                }
                doc.version = p.text_document.version;
                doc.analysis = None;
                dirty.insert(p.text_document.uri.as_str().to_string());
            }
        }
        DidCloseTextDocument::METHOD => {
            if let Ok(p) = serde_json::from_value::<lsp_types::DidCloseTextDocumentParams>(n.params)
            {
                docs.remove(p.text_document.uri.as_str());
                dirty.remove(p.text_document.uri.as_str());
                return Some(p.text_document.uri);
            }
        }
        _ => {}
    }
    None
}

fn answer(docs: &mut Docs, req: Request) -> Response {
    let id = req.id.clone();
    let result = match req.method.as_str() {
        HoverRequest::METHOD => at_position(docs, req.params, |doc, at, _| {
            serde_json::to_value(hover_at(doc, at))
        }),
        GotoDefinition::METHOD => at_position(docs, req.params, |doc, at, uri| {
            let locations = locate(doc, uri, at, true);
            serde_json::to_value(locations.map(GotoDefinitionResponse::Array))
        }),
        References::METHOD => at_position(docs, req.params, |doc, at, uri| {
            serde_json::to_value(locate(doc, uri, at, false))
        }),
        DocumentSymbolRequest::METHOD => with_document(docs, req.params, |doc| {
            serde_json::to_value(symbols(doc).map(DocumentSymbolResponse::Nested))
        }),
        Completion::METHOD => with_document(docs, req.params, |doc| {
            serde_json::to_value(CompletionResponse::Array(completion(doc)))
        }),
        Formatting::METHOD => {
            with_document(docs, req.params, |doc| serde_json::to_value(format(doc)))
        }
        CodeActionRequest::METHOD => code_actions(docs, req.params),
        SemanticTokensFullRequest::METHOD => with_document(docs, req.params, |doc| {
            let text = doc.text.clone();
            let data = tokens::tokens(&text, doc.analysis());
            serde_json::to_value(lsp_types::SemanticTokens {
                result_id: None,
                data,
            })
        }),
        _ => {
            return Response::new_err(
                id,
                ErrorCode::MethodNotFound as i32,
                format!("unhandled method {}", req.method),
            );
        }
    };
    match result {
        Some(Ok(v)) => Response::new_ok(id, v),
        Some(Err(e)) => Response::new_err(id, ErrorCode::InternalError as i32, e.to_string()),
        None => Response::new_err(
            id,
            ErrorCode::InvalidParams as i32,
            "unknown document or malformed parameters".into(),
        ),
    }
}

/// Runs `f` on the document named by `params.textDocument`.
fn with_document<T>(
    docs: &mut Docs,
    params: serde_json::Value,
    f: impl FnOnce(&mut Document) -> T,
) -> Option<T> {
    let id: lsp_types::TextDocumentIdentifier =
        serde_json::from_value(params.get("textDocument")?.clone()).ok()?;
    docs.get_mut(id.uri.as_str()).map(f)
}

/// Runs `f` on the document and the byte offset of a position request.
fn at_position<T>(
    docs: &mut Docs,
    params: serde_json::Value,
    f: impl FnOnce(&mut Document, usize, &Uri) -> T,
) -> Option<T> {
    // References' parameters extend these (`context`): read the common part.
    let p: TextDocumentPositionParams = serde_json::from_value(params).ok()?;
    let doc = docs.get_mut(p.text_document.uri.as_str())?;
    let at = text::offset(&doc.text, p.position);
    Some(f(doc, at, &p.text_document.uri))
}

/// The hover at byte `at`; from the last version that parsed when the
/// text does not parse (marked so), where the name is unchanged.
fn hover_at(doc: &mut Document, at: usize) -> Option<Hover> {
    let text = doc.text.clone();
    let (md, span) = match stale(doc) {
        None => hover::hover(&text, doc.analysis(), at)?,
        Some((last, unchanged)) => {
            let (md, old) = hover::hover(&last.text, &last.analysis, unchanged.to_old(at)?)?;
            let span = unchanged.to_new(old)?;
            (
                format!("*(as of the last version that parsed)*\n\n{md}"),
                span,
            )
        }
    };
    Some(Hover {
        contents: HoverContents::Markup(MarkupContent {
            kind: MarkupKind::Markdown,
            value: md,
        }),
        range: Some(text::range(&text, span)),
    })
}

/// The last version that parsed and how it maps onto the text, when the
/// text does not parse.
fn stale(doc: &mut Document) -> Option<(&LastParsed, Unchanged)> {
    if doc.analysis().model.is_some() {
        return None;
    }
    let last = doc.last_parsed.as_ref()?;
    let unchanged = Unchanged::of(&last.text, &doc.text);
    Some((last, unchanged))
}

fn locate(doc: &mut Document, uri: &Uri, at: usize, definition: bool) -> Option<Vec<Location>> {
    let text = doc.text.clone();
    let (a, at, map) = match stale(doc) {
        Some((last, unchanged)) => (&last.analysis, unchanged.to_old(at)?, Some(unchanged)),
        None => (doc.analysis(), at, None),
    };
    let new_span = |s: Span| map.map_or(Some(s), |m| m.to_new(s));
    let o = a.symbols.at(at)?;
    new_span(o.span)?;
    let found = if definition {
        a.symbols.declarations(&o.name, o.kind)
    } else {
        a.symbols.references(&o.name, o.kind)
    };
    Some(
        found
            .into_iter()
            .filter_map(|o| new_span(o.span))
            .map(|s| Location::new(uri.clone(), text::range(&text, s)))
            .collect(),
    )
}

fn symbols(doc: &mut Document) -> Option<Vec<DocumentSymbol>> {
    let text = doc.text.clone();
    let a = doc.analysis();
    let model = a.model.as_ref()?;
    let children: Vec<DocumentSymbol> = a
        .symbols
        .occurrences
        .iter()
        .filter(|o| o.declaration)
        .map(|o| {
            #[allow(deprecated)]
            DocumentSymbol {
                name: o.name.clone(),
                detail: Some(o.kind.word().into()),
                kind: match o.kind {
                    Kind::Parameter => SymbolKind::CONSTANT,
                    Kind::Medium => SymbolKind::OBJECT,
                    Kind::Relative | Kind::Component => SymbolKind::FIELD,
                    _ => SymbolKind::VARIABLE,
                },
                tags: None,
                deprecated: None,
                range: text::range(&text, o.item.join(o.span)),
                selection_range: text::range(&text, o.span),
                children: None,
            }
        })
        .collect();
    #[allow(deprecated)]
    Some(vec![DocumentSymbol {
        name: model.name.name.clone(),
        detail: Some("model".into()),
        kind: SymbolKind::MODULE,
        tags: None,
        deprecated: None,
        range: text::range(&text, model.span),
        selection_range: text::range(&text, model.name.span),
        children: Some(children),
    }])
}

fn completion(doc: &mut Document) -> Vec<CompletionItem> {
    let a = doc.analysis();
    let names = a
        .symbols
        .names()
        .into_iter()
        .map(|(name, kind)| CompletionItem {
            label: name,
            kind: Some(match kind {
                Kind::Parameter => CompletionItemKind::CONSTANT,
                Kind::Medium => CompletionItemKind::MODULE,
                Kind::Relative | Kind::Component => CompletionItemKind::FIELD,
                _ => CompletionItemKind::VARIABLE,
            }),
            detail: Some(kind.word().into()),
            ..Default::default()
        });
    let keywords = KEYWORDS.iter().map(|k| CompletionItem {
        label: (*k).into(),
        kind: Some(CompletionItemKind::KEYWORD),
        ..Default::default()
    });
    names.chain(keywords).collect()
}

fn code_actions(
    docs: &mut Docs,
    params: serde_json::Value,
) -> Option<serde_json::Result<serde_json::Value>> {
    let p: lsp_types::CodeActionParams = serde_json::from_value(params).ok()?;
    let doc = docs.get_mut(p.text_document.uri.as_str())?;
    let within = leeway_grammar::Span::new(
        text::offset(&doc.text, p.range.start),
        text::offset(&doc.text, p.range.end),
    );
    let text = doc.text.clone();
    let found = actions::actions(&p.text_document.uri, &text, doc.analysis(), within);
    Some(serde_json::to_value(found))
}

/// The whole document replaced by its canonical layout; nothing when it is
/// already so or does not parse.
fn format(doc: &Document) -> Option<Vec<TextEdit>> {
    let formatted = leeway_format::format(&doc.text).ok()?;
    if formatted == doc.text {
        return Some(Vec::new());
    }
    let end = text::position(&doc.text, doc.text.len());
    Some(vec![TextEdit::new(
        lsp_types::Range::new(lsp_types::Position::new(0, 0), end),
        formatted,
    )])
}
