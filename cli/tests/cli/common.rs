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

/// The catamaran of `tests/models/catamaran.som`: two thrusters, quadratic
/// drag, a constant surge force and a current of (0.2, −0.1) m/s.
pub const CATAMARAN: &str = "tests/models/catamaran.som";

/// Its true θ in the model's parameter order (X_0, X_u, X_uu, X_T, Y_v,
/// Y_vv, Y_ur, N_r, N_T).
pub const CATAMARAN_THETA: [f64; 9] = [0.05, -0.1, -0.05, 0.01, -0.3, -0.3, -0.5, -0.4, 0.002];

/// The catamaran's current (north, east), m/s.
pub const CATAMARAN_CURRENT: [f64; 2] = [0.2, -0.1];

/// Three catamaran runs of `n` samples as CSV text: thrust pulses (common
/// and differential) from different headings, the third astern (so that the
/// constant force is told apart from the current's moments), measurement
/// and process noise, a current that varies about its mean.
pub fn catamaran_csv(n: usize, seed: u64) -> String {
    use leeway_scenarios::synth::{TrueSystem, experiment};
    let src = std::fs::read_to_string(root().join(CATAMARAN)).unwrap_or_default();
    let c = leeway_structure::compile(&src, &Default::default());
    let model = Interpreter::new(c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics)));
    let system = TrueSystem {
        theta: CATAMARAN_THETA.to_vec(),
        h: 0.1,
        disturbance_mean: CATAMARAN_CURRENT.to_vec(),
        disturbance_std: vec![0.02; 2],
        disturbance_time: Vec::new(),
        state_noise: vec![0.01, 0.01, 0.002],
        heading_noise: 0.002,
        aux_noise: Vec::new(),
        process_noise: vec![0.002, 0.002, 0.0005],
    };
    let design = study::InputDesign {
        offset: [50.0, 0.0, 0.0],
        pulse: [30.0, 0.0, 40.0],
        width: (20, 80),
        smoothing: 0.15,
        x0: [3.0, 0.0, 0.0],
        sway_from_yaw: 0.0,
    };
    let runs: Vec<Experiment> = (0..3u64)
        .map(|k| {
            let thrust: Vec<Vec<f64>> = study::Pulses::new(&design, seed + 31 * k)
                .take(n)
                .map(|p| {
                    let common = if k == 2 { -p[0] } else { p[0] };
                    vec![common + p[2], common - p[2]]
                })
                .collect();
            let name = format!("run{}", k + 1);
            let x0 = [if k == 2 { -3.0 } else { 3.0 }, 0.0, 0.0];
            experiment(
                &model,
                &system,
                &name,
                &x0,
                2.0 * k as f64,
                &thrust,
                seed + k,
            )
            .0
        })
        .collect();
    csv_text(&model, &runs.iter().collect::<Vec<_>>())
}
