//! The check's power on a synthetic ferry sampled at 1 Hz (the ferry of
//! `examples/models/ferry.som`): a dynamic-positioning stretch between
//! open-loop pulses, an autopilot holding a course in waves, and open-loop
//! pulses alone.

use super::*;
use leeway_model::experiment::Experiment;
use std::f64::consts::PI;

const FERRY: &str = include_str!("../../../examples/models/ferry.som");

fn ferry() -> Ir {
    leeway_structure::compile(FERRY, &leeway_structure::CompileOptions::default())
        .ir
        .unwrap_or_else(|| panic!("the ferry compiles"))
}

/// A seeded generator of uniform and normal numbers.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * PI * b).cos()
    }
}

/// An angle in `(−π, π]`.
fn wrap(a: f64) -> f64 {
    a - 2.0 * PI * ((a + PI) / (2.0 * PI)).ceil() + 2.0 * PI
}

/// The ferry's nominal parameters (`ferry.som`).
const X: [f64; 4] = [-0.05, -0.05, 0.4, 6.7e-5];
const Y: [f64; 4] = [-0.15, -0.3, -0.5, 6e-5];
const N: [f64; 4] = [-0.3, -0.6, 0.02, 2e-5];

/// `u, v, r, ψ, north, east` and their derivatives under the forces `f`
/// (thrust and disturbance, body frame).
fn derivative(s: &[f64; 6], f: &[f64; 3]) -> [f64; 6] {
    let [u, v, r, psi, _, _] = *s;
    [
        X[0] * u + X[1] * u * u.abs() + X[2] * v * r + X[3] * f[0],
        Y[0] * v + Y[1] * v * v.abs() + Y[2] * u * r + Y[3] * f[1],
        N[0] * r + N[1] * r * r.abs() + N[2] * u * v + N[3] * f[2],
        r,
        u * psi.cos() - v * psi.sin(),
        u * psi.sin() + v * psi.cos(),
    ]
}

fn rk4(s: &[f64; 6], f: &[f64; 3], dt: f64) -> [f64; 6] {
    let add = |a: &[f64; 6], b: &[f64; 6], c: f64| std::array::from_fn(|i| a[i] + c * b[i]);
    let k1 = derivative(s, f);
    let k2 = derivative(&add(s, &k1, dt / 2.0), f);
    let k3 = derivative(&add(s, &k2, dt / 2.0), f);
    let k4 = derivative(&add(s, &k3, dt), f);
    std::array::from_fn(|i| s[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// Who sets the forces at a time.
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    /// Pulses: random levels held a few seconds, with the allocator's jitter.
    Pulses,
    /// Dynamic positioning: PID on the position (from the navigation
    /// filter) and heading errors, with velocity damping.
    Dp,
    /// Cruising on a fixed thrust, a PD autopilot on the heading error and
    /// the measured yaw rate setting the yaw moment.
    Autopilot,
    /// The same autopilot run at the log's rate (1 Hz), its rate term the
    /// heading's last step: a compass-only autopilot.
    CompassAutopilot,
}

/// `seconds` of the ferry, simulated at 100 Hz (RK4), the controller run
/// at 10 Hz, logged at 1 Hz: measured `u, v, r` and heading (wrapped to
/// `(−π, π]`), the commanded forces (the thrusters answer 1 s later). A
/// slow coloured disturbance (current, wind) and a wave-frequency one act
/// on every axis.
fn ferry_record(seed: u64, seconds: usize, mode: impl Fn(f64) -> Mode) -> Experiment {
    let ir = ferry();
    let mut e = Experiment::new(&ir, &format!("ferry/{seed}"), 1.0);
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x5DEE_CE66);
    let (dt, control_every, log_every) = (0.01, 10, 100);
    let mass = [1.0 / X[3], 1.0 / Y[3], 1.0 / N[3]];
    // The state: u, v, r, ψ, north, east; heading starts near the wrap.
    let mut s = [0.0, 0.0, 0.0, PI - 0.2, 0.0, 0.0];
    // Disturbances: slow (first order, 20 s), waves (resonance at 0.7 rad/s).
    let slow_sd = [150.0, 150.0, 600.0];
    let wave_sd = [100.0, 100.0, 800.0];
    let mut slow = [0.0f64; 3];
    let mut wave = [[0.0f64; 2]; 3];
    let (w0, zeta) = (0.7f64, 0.1f64);
    // Pulses.
    let mut level = [0.0f64; 3];
    let pulse = [500.0, 400.0, 1500.0];
    // Controller state.
    let mut command = [0.0f64; 3];
    let mut queue = std::collections::VecDeque::from(vec![[0.0f64; 3]; 100]);
    let mut estimate = [0.0f64; 2];
    let mut integral = [0.0f64; 3];
    let mut reference: Option<[f64; 3]> = None;
    let mut measured = [0.0f64; 4];
    let mut last_heading = s[3];
    let gains = |w: f64| (w * w, 0.1 * w * w * w, 2.0 * 0.9 * w);
    let steps = seconds * log_every;
    for step in 0..steps {
        let t = step as f64 * dt;
        if step % control_every == 0 {
            // The navigation filter's outputs.
            measured = [
                s[0] + 0.01 * rng.normal(),
                s[1] + 0.01 * rng.normal(),
                s[2] + 0.002 * rng.normal(),
                wrap(s[3] + 0.005 * rng.normal()),
            ];
            let gnss = [s[4] + 0.3 * rng.normal(), s[5] + 0.3 * rng.normal()];
            let (c, sn) = (measured[3].cos(), measured[3].sin());
            let h = dt * control_every as f64;
            for (i, g) in gnss.iter().enumerate() {
                let velocity = if i == 0 {
                    c * measured[0] - sn * measured[1]
                } else {
                    sn * measured[0] + c * measured[1]
                };
                estimate[i] += h * (velocity + 0.05 * (g - estimate[i]));
            }
            let m = mode(t);
            command = match m {
                Mode::Pulses => {
                    reference = None;
                    for (l, p) in level.iter_mut().zip(pulse) {
                        if rng.uniform() < 0.025 {
                            *l = p * (2.0 * rng.uniform() - 1.0);
                        }
                    }
                    std::array::from_fn(|i| level[i] + 0.02 * pulse[i] * rng.normal())
                }
                Mode::Dp => {
                    let hold = *reference.get_or_insert_with(|| {
                        integral = [0.0; 3];
                        [estimate[0], estimate[1], measured[3]]
                    });
                    let (en, ee) = (hold[0] - estimate[0], hold[1] - estimate[1]);
                    let error = [
                        c * en + sn * ee,
                        -sn * en + c * ee,
                        wrap(hold[2] - measured[3]),
                    ];
                    let rate = [measured[0], measured[1], measured[2]];
                    std::array::from_fn(|i| {
                        integral[i] += h * error[i];
                        let (p, int, d) = gains(if i == 2 { 0.3 } else { 0.2 });
                        mass[i] * (p * error[i] + int * integral[i] - d * rate[i])
                    })
                }
                Mode::Autopilot => {
                    let course = *reference.get_or_insert([0.0, 0.0, measured[3]]);
                    let (p, _, d) = gains(0.4);
                    [
                        800.0 + 15.0 * rng.normal(),
                        15.0 * rng.normal(),
                        mass[2] * (p * wrap(course[2] - measured[3]) - d * measured[2]),
                    ]
                }
                Mode::CompassAutopilot if step % log_every == 0 => {
                    let course = *reference.get_or_insert([0.0, 0.0, measured[3]]);
                    let (p, _, d) = gains(0.4);
                    let rate = wrap(measured[3] - last_heading);
                    last_heading = measured[3];
                    [
                        800.0 + 15.0 * rng.normal(),
                        15.0 * rng.normal(),
                        mass[2] * (p * wrap(course[2] - measured[3]) - d * rate),
                    ]
                }
                Mode::CompassAutopilot => command,
            };
        }
        if step % log_every == 0 {
            e.states[0].push(measured[0]);
            e.states[1].push(measured[1]);
            e.states[2].push(measured[2]);
            e.heading.push(measured[3]);
            for (column, c) in e.inputs.iter_mut().zip(command) {
                column.push(c);
            }
        }
        queue.push_back(command);
        let thrust = queue.pop_front().unwrap_or_default();
        let force: [f64; 3] = std::array::from_fn(|i| {
            let a = (-dt / 20.0f64).exp();
            slow[i] = a * slow[i] + slow_sd[i] * (1.0 - a * a).sqrt() * rng.normal();
            // x'' + 2ζω x' + ω² x = white, scaled to its standard deviation.
            let [x, xd] = wave[i];
            let drive = wave_sd[i] * (4.0 * zeta * w0 * w0 * w0 / dt).sqrt() * rng.normal();
            let xdd = drive - 2.0 * zeta * w0 * xd - w0 * w0 * x;
            wave[i] = [x + dt * (xd + dt * xdd), xd + dt * xdd];
            thrust[i] + slow[i] + wave[i][0]
        });
        s = rk4(&s, &force, dt);
    }
    e
}

/// The samples of `[from, to)` that a flagged stretch covers.
fn covered(found: &[Feedback], from: usize, to: usize) -> usize {
    found
        .iter()
        .map(|f| (f.last + 1).min(to).saturating_sub(f.first.max(from)))
        .sum()
}

/// Each judged window's shares.
fn shares(ir: &Ir, e: &Experiment) -> Vec<Judged> {
    let Some(mut scan) = FeedbackScan::new(ir, e) else {
        return Vec::new();
    };
    e.visit(&mut |row: &Row| scan.push(row));
    scan.windows().to_vec()
}

/// 600 s of pulses with 140 s of dynamic positioning from `from`.
fn dp_record(seed: u64, from: usize) -> Experiment {
    ferry_record(seed, 600, |t| {
        if (from as f64..(from + DP) as f64).contains(&t) {
            Mode::Dp
        } else {
            Mode::Pulses
        }
    })
}

/// The DP stretch's length, seconds.
const DP: usize = 140;

/// Where each seed's DP stretch begins: every place relative to the
/// windows (100 samples at 1 Hz) in steps of 13 s.
fn dp_from(seed: u64) -> usize {
    200 + 13 * seed as usize
}

#[test]
fn a_dp_stretch_at_1_hz_is_flagged_and_the_pulses_around_it_are_not() {
    let ir = ferry();
    for seed in 1..=6 {
        let from = dp_from(seed);
        let found = feedback(&ir, &dp_record(seed, from));
        let inside = covered(&found, from, from + DP);
        let outside = covered(&found, 0, 600) - inside;
        // Of two or three windows over the stretch, one is at least 70
        // samples of DP: at least half the stretch is flagged.
        assert!(2 * inside >= DP, "seed {seed}: {found:?}");
        // Only windows that reach into the stretch are flagged, and only
        // those mostly in it.
        assert!(
            found
                .iter()
                .all(|f| covered(std::slice::from_ref(f), from, from + DP) > 0)
        );
        // A window is 100 samples at 1 Hz: a flagged one reaches at most
        // one window beyond the stretch in all.
        assert!(outside <= 100, "seed {seed}: {found:?}");
    }
}

#[test]
fn an_autopilot_at_1_hz_in_waves_is_flagged() {
    let ir = ferry();
    for seed in 1..=4 {
        for mode in [Mode::Autopilot, Mode::CompassAutopilot] {
            let found = feedback(&ir, &ferry_record(seed, 600, |_| mode));
            assert!(covered(&found, 0, 600) >= 480, "seed {seed}: {found:?}");
            assert!(found.iter().all(|f| f.inputs == ["tau_n"]), "{found:?}");
        }
    }
}

#[test]
fn open_loop_pulses_at_1_hz_are_never_flagged() {
    let ir = ferry();
    for seed in 1..=8 {
        let e = ferry_record(seed, 900, |_| Mode::Pulses);
        assert_eq!(feedback(&ir, &e), vec![], "seed {seed}");
        // Every window was judged: the quiet is the test's, not a lack of
        // innovations.
        let windows = shares(&ir, &e);
        assert!(windows.len() >= 9, "{}", windows.len());
        assert!(
            windows.iter().all(|w| w.inputs.iter().all(Option::is_some)),
            "seed {seed}"
        );
    }
}

/// The figures of docs/logs.md: `cargo test -p leeway-estimate --lib
/// feedback::power::figures -- --ignored --nocapture`.
#[test]
#[ignore]
fn figures() {
    let ir = ferry();
    let show = |w: &Judged| {
        let s: Vec<String> = w
            .inputs
            .iter()
            .map(|x| {
                x.map_or("-".into(), |(e, r)| {
                    format!("{e:.3}{}", if r { "*" } else { "" })
                })
            })
            .collect();
        s.join(" ")
    };
    let (mut dp_least, mut open_most, mut flagged) = (f64::INFINITY, 0.0f64, 0);
    for seed in 1..=6 {
        let from = dp_from(seed);
        let e = dp_record(seed, from);
        for w in shares(&ir, &e) {
            let dp = (w.last + 1)
                .min(from + DP)
                .saturating_sub(w.first.max(from));
            let most = w.inputs.iter().flatten().map(|x| x.0).fold(0.0, f64::max);
            if dp == w.last + 1 - w.first {
                let least = w.inputs.iter().map(|x| x.map_or(0.0, |x| x.0));
                dp_least = least.fold(dp_least, f64::min);
            } else if dp == 0 {
                open_most = open_most.max(most);
            }
            eprintln!(
                "dp seed {seed} [{}, {}] dp {dp}: {}",
                w.first,
                w.last,
                show(&w)
            );
        }
        flagged += covered(&feedback(&ir, &e), from, from + DP);
    }
    eprintln!(
        "DP: whole windows explain at least {dp_least:.3}; open-loop windows at most {open_most:.3}; {:.0} % of DP samples flagged",
        100.0 * flagged as f64 / (6 * DP) as f64
    );
    for mode in [Mode::Autopilot, Mode::CompassAutopilot] {
        let mut least = f64::INFINITY;
        for seed in 1..=4 {
            for w in shares(&ir, &ferry_record(seed, 600, |_| mode)) {
                least = least.min(w.inputs[2].map_or(0.0, |x| x.0));
            }
        }
        eprintln!(
            "autopilot ({}): tau_n explained at least {least:.3}",
            if mode == Mode::Autopilot {
                "gyro"
            } else {
                "compass"
            }
        );
    }
    let mut most = 0.0f64;
    for seed in 1..=8 {
        for w in shares(&ir, &ferry_record(seed, 900, |_| Mode::Pulses)) {
            most = w.inputs.iter().flatten().map(|x| x.0).fold(most, f64::max);
        }
    }
    eprintln!("pulses: at most {most:.3} explained");
}
