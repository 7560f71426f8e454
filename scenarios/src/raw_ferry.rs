//! A ferry's raw ROS 2 topics, as a careful engineer would have to
//! pre-process them by hand: the thrust allocator's forces at 50 Hz with a
//! fast ripple and noise from cycle to cycle (the thrusters apply each
//! published value, so the force the hull feels is their mean over time),
//! the navigation filter's velocities at 5 Hz with white noise, the
//! heading as an ENU quaternion (ROS, REP 103) at 5 Hz, a mode topic at
//! 1 Hz, a 1 s dead time, and a stretch under dynamic positioning whose
//! controller acts on position and heading. The model steps by Euler on a
//! 1 s grid; the truth is RK4 at 100 Hz. [`RAW_MODEL`] is the model, and
//! [`write_raw_ferry`] writes the topics with their manifest.

use crate::ferry::{rk4, stamp_columns, wrap};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::FRAC_PI_2;
use std::fmt::Write as _;
use std::path::Path;

/// The RK4 step of the truth.
const FINE: f64 = 0.01;

/// The true parameters of a larger, slower ferry than [`crate::ferry`]'s
/// (time constants of 5 to 50 s, so that a 1 s Euler step fits it), in the
/// order of [`RAW_MODEL`]'s `nominal { }`.
pub const RAW_TRUTH: [(&str, f64); 12] = [
    ("X_u", -0.02),
    ("X_uu", -0.02),
    ("X_vr", 0.2),
    ("X_t", 2e-5),
    ("Y_v", -0.05),
    ("Y_vv", -0.1),
    ("Y_ur", -0.3),
    ("Y_t", 2e-5),
    ("N_r", -0.1),
    ("N_rr", -0.3),
    ("N_uv", 0.005),
    ("N_t", 6e-6),
];

/// The model the raw topics are read with: a 1 s grid, a 1 s dead time.
pub const RAW_MODEL: &str = "// A harbour ferry on a 1 s grid, read from its raw ROS 2 topics.
model RawFerry {
    step 1.0
    state u, v, r
    input tau_x, tau_y, tau_n
    heading psi integrates r
    delay tau_x 1.0 s
    delay tau_y 1.0 s
    delay tau_n 1.0 s

    der u = X_u*u + X_uu*u*|u| + X_vr*v*r + X_t*tau_x
    der v = Y_v*v + Y_vv*v*|v| + Y_ur*u*r + Y_t*tau_y
    der r = N_r*r + N_rr*r*|r| + N_uv*u*v + N_t*tau_n

    nominal { X_u = -0.02, X_uu = -0.02, X_vr = 0.2, X_t = 2e-5,
              Y_v = -0.05, Y_vv = -0.1, Y_ur = -0.3, Y_t = 2e-5,
              N_r = -0.1, N_rr = -0.3, N_uv = 0.005, N_t = 6e-6 }
}
";

/// What to write.
#[derive(Clone, Debug)]
pub struct RawFerry {
    /// The seed of every draw.
    pub seed: u64,
    /// The log's length, seconds.
    pub seconds: f64,
    /// The stretch under dynamic positioning, seconds from the start.
    pub dp: (f64, f64),
}

impl Default for RawFerry {
    fn default() -> RawFerry {
        RawFerry {
            seed: 1,
            seconds: 1800.0,
            dp: (700.0, 843.0),
        }
    }
}

/// The thrusters' dead time, seconds.
const DEAD_TIME: f64 = 1.0;
/// The open-loop force levels' ranges (N, N, N m).
const RANGE: [f64; 3] = [3000.0, 2500.0, 1500.0];
/// The allocator's ripple: amplitude as a share of the range, and its
/// frequency (Hz), far above the 1 s grid's band.
const RIPPLE: (f64, f64) = (0.3, 3.7);
/// The allocator's cycle-to-cycle noise, as a share of the range.
const FORCE_NOISE: f64 = 0.25;
/// The navigation filter's white noise on u, v (m/s), r (rad/s), and on ψ.
const NAV_NOISE: [f64; 4] = [0.03, 0.03, 0.004, 0.01];

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// `(u, v, r, ψ, north, east)` and its derivative under `tau`.
fn derivative(x: [f64; 6], tau: [f64; 3]) -> [f64; 6] {
    let p: Vec<f64> = RAW_TRUTH.iter().map(|(_, v)| *v).collect();
    let [u, v, r, psi, _, _] = x;
    [
        p[0] * u + p[1] * u * u.abs() + p[2] * v * r + p[3] * tau[0],
        p[4] * v + p[5] * v * v.abs() + p[6] * u * r + p[7] * tau[1],
        p[8] * r + p[9] * r * r.abs() + p[10] * u * v + p[11] * tau[2],
        r,
        u * psi.cos() - v * psi.sin(),
        u * psi.sin() + v * psi.cos(),
    ]
}

/// The dynamic-positioning controller: a PD on the position error (rotated
/// into the body frame) and on the heading error, from measured motion.
fn dp(x: [f64; 6], target: [f64; 3]) -> [f64; 3] {
    let [u, v, r, psi, n, e] = x;
    let (dn, de) = (target[0] - n, target[1] - e);
    let (ex, ey) = (
        dn * psi.cos() + de * psi.sin(),
        -dn * psi.sin() + de * psi.cos(),
    );
    [
        400.0 * ex - 6000.0 * u,
        400.0 * ey - 6000.0 * v,
        3000.0 * wrap(target[2] - psi) - 15000.0 * r,
    ]
    .map(|f: f64| f.clamp(-3000.0, 3000.0))
}

/// Stamps every `1/rate` seconds with ±20 % jitter.
fn stamps(seconds: f64, rate: f64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut out = Vec::new();
    let mut t = 0.0;
    while t <= seconds {
        out.push(t);
        t += (1.0 + 0.2 * rng.random_range(-1.0..1.0)) / rate;
    }
    out
}

/// The topics as CSV text.
struct Topics {
    nav: String,
    imu: String,
    tau: String,
    mode: String,
}

fn simulate(spec: &RawFerry) -> Topics {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let publish = stamps(spec.seconds, 50.0, &mut rng);
    let nav_t = stamps(spec.seconds, 5.0, &mut rng);
    let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let n = (spec.seconds / FINE).round() as usize + 1;
    let mut x = [1.0, 0.0, 0.0, 0.5, 0.0, 0.0];
    let (mut level, mut until) = ([0.0; 3], 0.0);
    let mut target = [0.0; 3];
    let mut published: Vec<[f64; 3]> = Vec::with_capacity(publish.len());
    let mut acting = 0;
    let mut states = Vec::with_capacity(n);
    for k in 0..n {
        let t = k as f64 * FINE;
        if t >= until {
            level = std::array::from_fn(|i| RANGE[i] * rng.random_range(-1.0..1.0));
            until = t + rng.random_range(10.0..40.0);
        }
        let in_dp = (spec.dp.0..spec.dp.1).contains(&t);
        if in_dp && (t - spec.dp.0).abs() < FINE / 2.0 {
            target = [x[4], x[5], x[3]];
        }
        while published.len() < publish.len() && publish[published.len()] <= t + 1e-9 {
            let base = if in_dp {
                // The controller reads the navigation filter: noisy motion.
                let mut seen = x;
                for (s, sigma) in seen.iter_mut().zip(NAV_NOISE) {
                    *s += sigma * normal(&mut rng);
                }
                dp(seen, target)
            } else {
                level
            };
            let ts = publish[published.len()];
            published.push(std::array::from_fn(|i| {
                let ripple =
                    RIPPLE.0 * (std::f64::consts::TAU * RIPPLE.1 * ts + phase + i as f64).sin();
                base[i] + RANGE[i] * (ripple + FORCE_NOISE * normal(&mut rng))
            }));
        }
        while acting < published.len() && publish[acting] <= t - DEAD_TIME + 1e-9 {
            acting += 1;
        }
        let force = acting.checked_sub(1).map_or([0.0; 3], |j| published[j]);
        states.push(x);
        x = rk4(derivative, x, force, FINE);
    }
    let at = |t: f64| -> [f64; 6] {
        let s = t / FINE;
        let k = (s.floor() as usize).min(states.len() - 2);
        let w = s - k as f64;
        std::array::from_fn(|i| states[k][i] + w * (states[k + 1][i] - states[k][i]))
    };
    let mut nav = String::from("secs,nsecs,u,v,r\n");
    let mut imu =
        String::from("secs,nsecs,orientation.x,orientation.y,orientation.z,orientation.w\n");
    for &t in &nav_t {
        let x = at(t);
        let (s, ns) = stamp_columns(t);
        let m: Vec<f64> = (0..3)
            .map(|i| x[i] + NAV_NOISE[i] * normal(&mut rng))
            .collect();
        let _ = writeln!(nav, "{s},{ns},{},{},{}", m[0], m[1], m[2]);
        // ENU: the yaw from east, counter-clockwise.
        let yaw = wrap(FRAC_PI_2 - (x[3] + NAV_NOISE[3] * normal(&mut rng)));
        let _ = writeln!(
            imu,
            "{s},{ns},0,0,{},{}",
            (yaw / 2.0).sin(),
            (yaw / 2.0).cos()
        );
    }
    let mut tau = String::from("secs,nsecs,Fx,Fy,Mz\n");
    for (&t, f) in publish.iter().zip(&published) {
        let (s, ns) = stamp_columns(t);
        let _ = writeln!(tau, "{s},{ns},{},{},{}", f[0], f[1], f[2]);
    }
    let mut mode = String::from("secs,nsecs,dp\n");
    for k in 0..=(spec.seconds as i64) {
        let t = k as f64;
        let (s, ns) = stamp_columns(t);
        let on = i32::from((spec.dp.0..spec.dp.1).contains(&t));
        let _ = writeln!(mode, "{s},{ns},{on}");
    }
    Topics {
        nav,
        imu,
        tau,
        mode,
    }
}

/// The manifest that reads the raw topics, leaving the DP stretch out.
pub const RAW_MANIFEST: &str = "# A ferry's raw ROS 2 topics (docs/logs.md).
experiment = \"ferry\"

[sources.nav]
file = \"nav.csv\"
time = [\"secs\", \"nsecs\"]

[sources.imu]
file = \"imu.csv\"
time = [\"secs\", \"nsecs\"]

[sources.tau]
file = \"tau.csv\"
time = [\"secs\", \"nsecs\"]

[sources.mode]
file = \"mode.csv\"
time = [\"secs\", \"nsecs\"]

[signals]
u = \"nav:u\"
v = \"nav:v\"
r = \"nav:r\"
psi = { from = \"imu:orientation\", as = \"yaw\", frame = \"enu\" }
tau_x = \"tau:Fx\"
tau_y = \"tau:Fy\"
tau_n = \"tau:Mz\"

[[keep]]                      # joystick only: the DP controller is in the loop otherwise
when = \"mode:dp\"
equals = 0
";

/// Writes `nav.csv`, `imu.csv`, `tau.csv`, `mode.csv`, the manifest
/// `ferry.toml` and the model `raw-ferry.som` into `dir`.
pub fn write_raw_ferry(dir: &Path, spec: &RawFerry) -> std::io::Result<()> {
    let t = simulate(spec);
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join("nav.csv"), t.nav)?;
    std::fs::write(dir.join("imu.csv"), t.imu)?;
    std::fs::write(dir.join("tau.csv"), t.tau)?;
    std::fs::write(dir.join("mode.csv"), t.mode)?;
    std::fs::write(dir.join("ferry.toml"), RAW_MANIFEST)?;
    std::fs::write(dir.join("raw-ferry.som"), RAW_MODEL)?;
    Ok(())
}
