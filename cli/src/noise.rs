//! The noises of `leeway simulate`: `--disturbance-std NAME=STD,...`,
//! `--correlation-time NAME=SECONDS,...` and `--noise NAME=STD,...`, read
//! by the rule of `leeway_model::given::simulation_noise` (the one Python
//! follows) and its problems worded as the command line's.

use crate::problem::Problem;
use leeway_model::given::{NoiseOption, SimulationNoise, simulation_noise};
use leeway_structure::ir::Ir;

/// The noises given on the command line.
pub fn given(
    ir: &Ir,
    disturbance_std: &[String],
    correlation_time: &[String],
    sensors: &[String],
) -> Result<SimulationNoise, Problem> {
    let std = items(ir, NoiseOption::DisturbanceStd, disturbance_std)?;
    let time = items(ir, NoiseOption::CorrelationTime, correlation_time)?;
    let sensors = items(ir, NoiseOption::Sensor, sensors)?;
    simulation_noise(ir, &named(&std), &named(&time), &named(&sensors)).map_err(|p| {
        let item = match p.option {
            NoiseOption::DisturbanceStd => std[p.index].2,
            NoiseOption::CorrelationTime => time[p.index].2,
            NoiseOption::Sensor => sensors[p.index].2,
        };
        problem(ir, p.option, item, &p.reason)
    })
}

fn named<'a>(items: &[(&'a str, f64, &str)]) -> Vec<(&'a str, f64)> {
    items.iter().map(|&(n, v, _)| (n, v)).collect()
}

/// The flag of an option.
fn flag(option: NoiseOption) -> &'static str {
    match option {
        NoiseOption::DisturbanceStd => "--disturbance-std",
        NoiseOption::CorrelationTime => "--correlation-time",
        NoiseOption::Sensor => "--noise",
    }
}

/// One problem with an item, hinted with the names the option takes.
fn problem(ir: &Ir, option: NoiseOption, item: &str, why: &str) -> Problem {
    let mut hint = option.hint(ir);
    if option == NoiseOption::CorrelationTime {
        hint.push_str("; a correlation time shapes a component given a --disturbance-std");
    }
    Problem::error(
        "invalid-option",
        format!("{} `{item}`: {why}", flag(option)),
    )
    .help(hint)
}

/// `NAME=VALUE` items, comma-separated, as (name, value, item).
fn items<'a>(
    ir: &Ir,
    option: NoiseOption,
    specs: &'a [String],
) -> Result<Vec<(&'a str, f64, &'a str)>, Problem> {
    let example = match option {
        NoiseOption::DisturbanceStd => "NAME=STD (e.g. current.north=0.03 or current=0.03)",
        NoiseOption::CorrelationTime => "NAME=SECONDS (e.g. current=60)",
        NoiseOption::Sensor => "NAME=STD (e.g. u=0.01,psi=0.005)",
    };
    specs
        .iter()
        .flat_map(|spec| spec.split(','))
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|item| {
            let Some((name, value)) = item.split_once('=') else {
                return Err(problem(ir, option, item, &format!("expected {example}")));
            };
            let value = value.trim();
            match value.parse::<f64>() {
                Ok(v) => Ok((name.trim(), v, item)),
                Err(_) => Err(problem(
                    ir,
                    option,
                    item,
                    &format!("`{value}` is not a number"),
                )),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ship() -> Ir {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/ship.som");
        let c = leeway_structure::compile(
            &std::fs::read_to_string(path).unwrap_or_default(),
            &Default::default(),
        );
        c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
    }

    fn error(std: &str, time: &str, noise: &str) -> Option<String> {
        let list = |s: &str| -> Vec<String> {
            if s.is_empty() {
                Vec::new()
            } else {
                vec![s.to_string()]
            }
        };
        given(&ship(), &list(std), &list(time), &list(noise))
            .err()
            .map(|p| p.message)
    }

    #[test]
    fn lists_are_read_by_name() {
        let noise = given(
            &ship(),
            &["current=0.03".into(), "wind.wind_n=0.5".into()],
            &["north=60, east=30".into()],
            &["u=0.01,psi=0.005".into()],
        );
        let noise = noise.unwrap_or_default();
        assert_eq!(noise.disturbance_std, vec![0.03, 0.03, 0.5, 0.0]);
        assert_eq!(noise.correlation_time, vec![60.0, 30.0, 0.0, 0.0]);
        assert_eq!((noise.states[0], noise.heading), (0.01, 0.005));
    }

    #[test]
    fn problems_name_the_flag_and_the_item() {
        assert_eq!(
            error("current.north=x", "", "").as_deref(),
            Some("--disturbance-std `current.north=x`: `x` is not a number")
        );
        assert_eq!(
            error("", "", "u").as_deref(),
            Some("--noise `u`: expected NAME=STD (e.g. u=0.01,psi=0.005)")
        );
        assert_eq!(
            error("current=0.1", "current=-5", "").as_deref(),
            Some(
                "--correlation-time `current=-5`: -5 is negative: a correlation time is at least 0 s (0: independent samples)"
            )
        );
        assert_eq!(
            error("", "", "u=0.1,current=0.1").as_deref(),
            Some("--noise `current=0.1`: `current` is not measured: no sensor records it")
        );
    }
}
