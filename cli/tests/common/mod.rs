//! Helpers shared by the CLI's end-to-end tests: scratch directories, running
//! the built binary, and synthetic ship data written as CSV.
#![allow(dead_code)] // each test crate uses its own subset

use leeway_data::write_csv;
use leeway_model::Experiment;
use leeway_model::Interpreter;
use leeway_scenarios::study;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A scratch directory, removed when dropped.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("leeway-cli-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        Scratch(dir)
    }
    pub fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
    pub fn write(&self, file: &str, text: &str) -> String {
        let p = self.path(file);
        std::fs::write(&p, text).unwrap_or_else(|e| panic!("{e}"));
        p.display().to_string()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub const SHIP: &str = "examples/models/ship.som";

/// Runs `leeway ARGS` from the workspace root.
pub fn leeway(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_leeway"))
        .args(args)
        .current_dir(root())
        .env_remove("NO_COLOR")
        .output()
        .expect("run leeway")
}

pub fn code(o: &Output) -> i32 {
    o.status.code().expect("exit code")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn json(o: &Output) -> Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("stdout is not JSON ({e}): {}\n{}", stdout(o), stderr(o)))
}

pub fn no_panic(o: &Output) {
    assert!(!stderr(o).contains("panicked"), "{}", stderr(o));
}

pub fn ship() -> Interpreter {
    let src = std::fs::read_to_string(root().join(SHIP)).unwrap_or_default();
    let c = leeway_structure::compile(&src, &Default::default());
    Interpreter::new(c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics)))
}

pub fn csv_text(model: &Interpreter, experiments: &[&Experiment]) -> String {
    let mut buf = Vec::new();
    write_csv(leeway_model::Model::ir(model), experiments, 0.0, &mut buf)
        .unwrap_or_else(|e| panic!("{e}"));
    String::from_utf8(buf).unwrap_or_else(|e| panic!("{e}"))
}

/// One estimation experiment of the study as CSV text.
pub fn estimation_csv(n: usize, wind: f64, seed: u64) -> String {
    let model = ship();
    let (e, _) =
        study::estimation_experiment(&model, &study::InputDesign::default(), wind, n, seed);
    csv_text(&model, &[&e])
}

/// θ0 of the paper as a plain parameter file.
pub fn true_params() -> String {
    let model = ship();
    let ir = leeway_model::Model::ir(&model);
    let entries: Vec<String> = ir
        .parameters
        .iter()
        .zip(study::THETA0)
        .map(|(p, v)| format!("  \"{}\": {v:?}", p.name))
        .collect();
    format!("{{\n{}\n}}\n", entries.join(",\n"))
}
