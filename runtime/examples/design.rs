//! Input-design search: margins, IV3 spread and fits for candidate designs.
#![allow(clippy::unwrap_used)] // an exploration script: a panic is its error report
use leeway_runtime::estimate::{Method, Options, estimate};
use leeway_runtime::simulate::{Disturbances, fits, simulate};
use leeway_runtime::study::{self, InputDesign};
use leeway_runtime::{Interpreter, Source};
fn parse3(s: &str) -> [f64; 3] {
    let v: Vec<f64> = s.split(',').map(|x| x.parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let d = InputDesign {
        offset: parse3(&a[1]),
        pulse: parse3(&a[2]),
        x0: parse3(&a[3]),
        width: (a[4].parse().unwrap(), a[5].parse().unwrap()),
        smoothing: a[6].parse().unwrap(),
        sway_from_yaw: a.get(8).map(|s| s.parse().unwrap()).unwrap_or(0.0),
    };
    let n: usize = a.get(7).map(|s| s.parse().unwrap()).unwrap_or(2000);
    let src = std::fs::read_to_string("examples/models/ship.som").unwrap();
    let m = Interpreter::new(
        leeway_runtime::structure::compile(&src, &Default::default())
            .ir
            .unwrap(),
    );
    let val = study::validation_experiment(&m, 1000);
    for wind in [1.0, 10.0] {
        let mut worst = [f64::INFINITY; 4];
        let (mut rs, mut rss, mut cnt) = (0.0, 0.0, 0.0);
        let mut out = vec![];
        for seed in 0..6u64 {
            let (e, t) = study::estimation_experiment(&m, &d, wind, n, seed);
            for k in 0..t.heading.len() {
                let (c, s) = (t.heading[k].cos(), t.heading[k].sin());
                let (u, v, r) = (t.states[0][k], t.states[1][k], t.states[2][k]);
                let dd = |i: usize| t.disturbances[i][k];
                for (w, x) in worst.iter_mut().zip([
                    u - (c * dd(0) + s * dd(1)),
                    v - (-s * dd(0) + c * dd(1)),
                    u - (c * dd(2) + s * dd(3)),
                    v - (-s * dd(2) + c * dd(3)),
                ]) {
                    *w = w.min(x);
                }
                rs += r;
                rss += r * r;
                cnt += 1.0;
            }
            for meth in Method::ALL {
                let r = estimate(
                    &m,
                    &[&e as &dyn Source],
                    &Options {
                        method: meth,
                        aggregate: true,
                        covariance: false,
                        max_refinements: 4,
                        ..Default::default()
                    },
                );
                let (f, err) = match r {
                    Ok(est) => {
                        let sim = simulate(&m, &est.theta, &val, Disturbances::None);
                        (
                            fits(&val, &sim),
                            est.theta
                                .iter()
                                .zip(&study::THETA0)
                                .enumerate()
                                .filter(|(i, _)| ![3usize, 9, 15].contains(i))
                                .map(|(_, (a, b))| ((a - b) / b).abs())
                                .sum::<f64>()
                                / 14.0,
                        )
                    }
                    Err(_) => (vec![f64::NAN; 3], f64::NAN),
                };
                out.push((meth, f, err));
            }
        }
        let rm = rs / cnt;
        println!(
            "wind {wind}: min wu {:.2} wv {:.2} au {:.2} av {:.2}; r mean {:.3} sd {:.3}",
            worst[0],
            worst[1],
            worst[2],
            worst[3],
            rm,
            (rss / cnt - rm * rm).sqrt()
        );
        for meth in Method::ALL {
            let v: Vec<&(Method, Vec<f64>, f64)> = out.iter().filter(|x| x.0 == meth).collect();
            let med = |mut x: Vec<f64>| {
                x.sort_by(|a, b| a.total_cmp(b));
                x[x.len() / 2]
            };
            println!(
                "  {meth:?}: median fit u {:.1} v {:.1} r {:.1}; median err {:.3}",
                med(v.iter().map(|x| x.1[0]).collect()),
                med(v.iter().map(|x| x.1[1]).collect()),
                med(v.iter().map(|x| x.1[2]).collect()),
                med(v.iter().map(|x| x.2).collect())
            );
        }
    }
}
