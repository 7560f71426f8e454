//! Models and plans for the tests.

use leeway_design::design::{DesignOptions, design};
use leeway_design::error::DesignError;
use leeway_design::plan::{Conditions, parse};
use leeway_design::report::Design;
use leeway_model::Interpreter;
use leeway_model::model::Model;

/// A model of the repository (`examples/models/rov.som`, `tests/models/...`).
pub fn model(path: &str) -> Interpreter {
    let file = format!("{}/../{path}", env!("CARGO_MANIFEST_DIR"));
    let source = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let c = leeway_structure::compile(&source, &Default::default());
    Interpreter::new(c.ir.unwrap_or_else(|| panic!("{file}: {:?}", c.diagnostics)))
}

/// A plan file of the repository, read against `model`, its budget
/// replaced by `samples` per experiment (tests run short trials).
pub fn conditions(
    model: &Interpreter,
    plan: &str,
    samples: Option<usize>,
) -> Result<Conditions, DesignError> {
    let file = format!("{}/../{plan}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let mut plan = parse(&text, false)?;
    if let Some(n) = samples {
        plan.budget = Some(leeway_design::plan::Budget {
            time: None,
            samples: Some(n),
        });
    }
    plan.conditions(model.ir())
}

/// The design of `model` under `plan` with `samples` per experiment and a
/// small pilot.
pub fn designed(model: &Interpreter, plan: &str, samples: usize, pilot: usize) -> Design {
    let c = conditions(model, plan, Some(samples)).unwrap_or_else(|e| panic!("{plan}: {e:?}"));
    let options = DesignOptions {
        pilot,
        ..Default::default()
    };
    design(model, &c, &options).unwrap_or_else(|e| panic!("{plan}: {e:?}"))
}

/// The survey boat (`design/tests/fixtures`) with `seconds` at sea, its
/// nominal θ the truth (`prior` 0), and design options without a pilot.
pub fn survey_boat(seconds: f64) -> (Interpreter, Conditions, DesignOptions) {
    let boat = model("design/tests/fixtures/survey_boat.som");
    let mut c = conditions(&boat, "design/tests/fixtures/survey_boat.toml", None)
        .expect("the survey boat's plan");
    c.budget = leeway_design::bounds::BudgetRule::Time(seconds);
    c.prior = 0.0;
    let options = DesignOptions {
        pilot: 0,
        ..Default::default()
    };
    (boat, c, options)
}
