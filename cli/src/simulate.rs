//! `leeway simulate MODEL --params EST.json --input IN.csv [--out OUT.csv]`:
//! simulate the model with the given θ on an input file, from its first row
//! (see `input.rs` for what the file holds), and write the trajectory as a
//! CSV data file; with `--disturbance-std` or `--noise` (`noise.rs`), the
//! craft under varying disturbances as its sensors record it, seeded
//! (`leeway_scenarios::noisy`). Exit 0 on success, 1 when the simulation diverges (the rows
//! before the divergence are still written), 2 on any model, file or option error.

use crate::disturbances;
use crate::files::write_output;
use crate::input::{initial_values, load_input};
use crate::model::load;
use crate::noise;
use crate::options::load_options;
use crate::options::positive;
use crate::output::{Status, err, headline, io_reason, out, plain, stderr_style, warning_text};
use crate::problem::{Failure, Problem};
use leeway_data::write_csv;
use leeway_model::Interpreter;
use leeway_model::experiment::Source;
use leeway_model::given::Origin;
use leeway_model::simulate::Disturbances;
use leeway_model::simulate::simulate_written;
use leeway_model::warning::Warning;
use leeway_scenarios::noisy::simulate_noisy;
use std::path::PathBuf;

/// Arguments of `leeway simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// θ: the output of `leeway estimate --json`, or `{"name": value}` with every parameter.
    #[arg(long, value_name = "FILE.json")]
    pub params: PathBuf,
    /// The input (CSV): every input column on every row; the states and heading
    /// on the first row (or --x0); measured disturbances and rotation columns
    /// on every row.
    #[arg(long, value_name = "IN.csv")]
    pub input: PathBuf,
    /// Write the trajectory here instead of stdout.
    #[arg(long, value_name = "OUT.csv")]
    pub out: Option<PathBuf>,
    /// Initial values, e.g. `u=5,v=0,r=0.1,psi=0` (override the first row of the input).
    #[arg(long = "x0", value_name = "NAME=VALUE,...")]
    pub x0: Vec<String>,
    /// A constant unmeasured disturbance component, e.g. `current.north=0.2`
    /// (earth frame for earth-fixed media), or `zero` for none. Components
    /// not given take the means of the estimate given as --params, else zero
    /// (with a warning).
    #[arg(long = "disturbance", value_name = "NAME=VALUE,...")]
    pub disturbances: Vec<String>,
    /// Sample time for an input without a time column when the model declares no `step`.
    #[arg(long, value_name = "H", value_parser = positive)]
    pub step: Option<f64>,
    /// How much a disturbance component varies about its mean (std), e.g.
    /// `current.north=0.03`; a medium's name (`current=0.03`) gives all its
    /// components. The mean is --disturbance's (unmeasured) or the input's
    /// values (measured: the craft feels and the sensor records the
    /// variation).
    #[arg(long = "disturbance-std", value_name = "NAME=STD,...")]
    pub disturbance_std: Vec<String>,
    /// Correlation time of a varying component in seconds (first-order
    /// Gauss–Markov), e.g. `current=60`; default 0: independent samples.
    #[arg(long = "correlation-time", value_name = "NAME=SECONDS,...")]
    pub correlation_time: Vec<String>,
    /// Measurement noise (std) of a state, the heading or a measured
    /// disturbance's sensor, e.g. `u=0.01,psi=0.005,wind=0.2`: the output
    /// holds the measured values.
    #[arg(long = "noise", value_name = "NAME=STD,...")]
    pub noise: Vec<String>,
    /// Seed of the varying disturbances and the noise: the same seed, the
    /// same output.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
}

/// Runs `leeway simulate`.
pub fn run(args: &SimulateArgs) -> Status {
    let style = stderr_style();
    let mut warnings: Vec<Warning> = Vec::new();
    let result = execute(args, &mut warnings);
    for w in &warnings {
        err(&warning_text(style, w, false));
    }
    match result {
        Ok(status) => status,
        Err(f) => {
            err(&f.render(style, "simulated"));
            f.status()
        }
    }
}

fn execute(args: &SimulateArgs, warnings: &mut Vec<Warning>) -> Result<Status, Failure> {
    let loaded = load(&args.model, false)?;
    warnings.extend(plain("model", loaded.warnings));
    let ir = loaded.ir;
    let options = load_options(&ir, args.step, None)?;
    let file = crate::params::read_file(&args.params, &ir, "--params")?;
    let x0 = initial_values(&ir, &args.x0)?;
    let given = disturbances::given(&ir, &args.disturbances)?;
    let noise = noise::given(
        &ir,
        &args.disturbance_std,
        &args.correlation_time,
        &args.noise,
    )?;
    let (held, warning) = disturbances::held(&ir, &given, &file, &args.params);
    // Said when values came from the estimate (the user may not expect it);
    // a default zero is warned of.
    let from_estimate = held.origins.contains(&Some(Origin::Estimate));
    match (
        warning,
        disturbances::described(&ir, &held).filter(|_| from_estimate),
    ) {
        (Some(w), _) => warnings.push(w),
        (None, Some(line)) => err(&headline(
            stderr_style(),
            "note",
            None,
            &format!("disturbances held: {line}"),
        )),
        (None, None) => {}
    }
    let input = load_input(&args.input, &ir, &options, &x0)?;
    let model = Interpreter::new(ir.clone());
    let e = &input.experiment;
    // With dead times the simulation starts `d_max` rows in: the rows before
    // only supply the delayed inputs, and the output's time starts there.
    let lead = leeway_model::delay::dead_times(&ir, &e.name, e.h).map_err(|d| {
        Problem::error("invalid-delay", d.to_string())
            .at(args.input.display().to_string())
            .help("declare the dead time in steps, or in seconds that are a whole number of the input's sample time")
    })?;
    // Rows before the longest dead time only feed the delayed inputs: a
    // record no longer than it has nothing to simulate.
    let samples = e.len();
    if lead.max > 0 && samples <= lead.max {
        let input = lead
            .lags
            .iter()
            .position(|&d| d == lead.max)
            .and_then(|i| ir.inputs.get(i))
            .map_or(String::new(), |name| format!(" (of `{name}`)"));
        let plural = if samples == 1 { "" } else { "s" };
        return Err(Problem::error(
            "too-few-samples",
            format!(
                "the input has {samples} sample{plural}, no more than the model's longest dead time{input} of {} samples ({} s): nothing would be simulated",
                lead.max,
                lead.max as f64 * e.h
            ),
        )
        .at(args.input.display().to_string())
        .help(format!(
            "give an input of more than {} samples: the first {} only feed the delayed inputs, the trajectory starts after them",
            lead.max, lead.max
        ))
        .into());
    }
    let t0 = match lead.max {
        0 => input.t0,
        d => input.t0 + d as f64 * e.h,
    };
    // Without noise, the plain simulation: the bits it always wrote.
    let written = if noise.is_quiet() {
        simulate_written(&model, &file.theta, e, Disturbances::Constant(&held.values))
    } else {
        simulate_noisy(&model, &file.theta, e, &held.values, &noise, args.seed)
    };
    let (result, finite) = (written.experiment, written.samples);
    let mut buffer = Vec::new();
    write_csv(&ir, &[&result], t0, &mut buffer)
        .map_err(|error| Problem::error("io", format!("cannot write the trajectory: {error}")))?;
    match &args.out {
        Some(path) => write_output(path, &buffer).map_err(|error| {
            Problem::error(
                "io",
                format!("cannot write `{}`: {}", path.display(), io_reason(&error)),
            )
            .at(path.display().to_string())
        })?,
        None => out(&String::from_utf8_lossy(&buffer)),
    }
    if written.diverged {
        let t = t0 + finite as f64 * e.h;
        return Err(Problem {
            status: Status::Unsupported,
            ..Problem::error(
                "diverged",
                format!(
                    "the simulation diverged at sample {finite} (time {t}): the states left the finite numbers; the {finite} rows before are written"
                ),
            )
            .help("check the parameters (a positive damping term makes the model unstable) and the units of the input")
        }
        .into());
    }
    Ok(Status::Success)
}
