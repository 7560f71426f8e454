//! A small autonomous ferry's log as its robot writes it: ROS 2 topics
//! exported one CSV per topic, each at its own rate with jitter, stamps in
//! two integer columns (`secs`, `nsecs`), a human-readable local time that
//! goes backwards, the thrust allocator's forces stalling for a second, a
//! 5.8 s hole in the velocities, the thrusters answering a second late, and
//! a stretch under dynamic positioning (the forces then computed from the
//! measured motion: closed loop). The truth is integrated by RK4 at 100 Hz
//! in continuous time — not the model's own Euler step — so an estimate
//! meets model error, as on real data. With `aligned`, every topic is
//! stamped on the model's grid (velocities and forces at 10 Hz, heading at
//! 20 Hz, no stalls) and `uniform.csv` holds the same samples on one grid,
//! split at the same hole: reading the topics must give exactly it.
//! `examples/models/ferry.som` is the model; docs/logs.md walks through it.

use leeway_data::DataError;
use leeway_logs::bag::write::{MessageKind, TopicSeries, write_bag};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

/// The log's first stamp: 2026-05-14T08:00:00Z.
pub const EPOCH_SECONDS: i64 = 1_778_745_600;
/// The model's sample time.
pub const GRID: f64 = 0.1;
/// The RK4 step of the truth.
const FINE: f64 = 0.01;

/// The true parameters, per unit mass and inertia (a 15 t ferry with 3 kN
/// thrusters), in the order of `ferry.som`'s `nominal { }`.
pub const TRUTH: [(&str, f64); 12] = [
    ("X_u", -0.05),
    ("X_uu", -0.05),
    ("X_vr", 0.4),
    ("X_t", 6.7e-5),
    ("Y_v", -0.15),
    ("Y_vv", -0.3),
    ("Y_ur", -0.5),
    ("Y_t", 6e-5),
    ("N_r", -0.3),
    ("N_rr", -0.6),
    ("N_uv", 0.02),
    ("N_t", 2e-5),
];

/// What to write.
#[derive(Clone, Debug)]
pub struct FerryLog {
    /// The seed of every draw.
    pub seed: u64,
    /// The log's length, seconds.
    pub seconds: f64,
    /// The thrusters' dead time, seconds.
    pub dead_time: f64,
    /// Every topic on the grid, and `uniform.csv` beside them.
    pub aligned: bool,
    /// The stretch under dynamic positioning, seconds from the start.
    pub closed_loop: (f64, f64),
    /// The hole in the velocity topic, seconds from the start.
    pub hole: (f64, f64),
}

impl Default for FerryLog {
    fn default() -> FerryLog {
        FerryLog {
            seed: 1,
            seconds: 1200.0,
            dead_time: 1.0,
            aligned: false,
            closed_loop: (700.0, 850.0),
            hole: (400.0, 405.8),
        }
    }
}

/// The state `(u, v, r, psi)` and its derivative under `tau`.
fn derivative(x: [f64; 4], tau: [f64; 3]) -> [f64; 4] {
    let p: Vec<f64> = TRUTH.iter().map(|(_, v)| *v).collect();
    let [u, v, r, _] = x;
    [
        p[0] * u + p[1] * u * u.abs() + p[2] * v * r + p[3] * tau[0],
        p[4] * v + p[5] * v * v.abs() + p[6] * u * r + p[7] * tau[1],
        p[8] * r + p[9] * r * r.abs() + p[10] * u * v + p[11] * tau[2],
        r,
    ]
}

/// One RK4 step of `f` (the state's derivative under the held force `tau`).
pub(crate) fn rk4<const N: usize>(
    f: impl Fn([f64; N], [f64; 3]) -> [f64; N],
    x: [f64; N],
    tau: [f64; 3],
    h: f64,
) -> [f64; N] {
    let add = |a: [f64; N], b: [f64; N], s: f64| std::array::from_fn(|i| a[i] + s * b[i]);
    let k1 = f(x, tau);
    let k2 = f(add(x, k1, h / 2.0), tau);
    let k3 = f(add(x, k2, h / 2.0), tau);
    let k4 = f(add(x, k3, h), tau);
    std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// The truth at every fine step: states and the navigation filter's error
/// on `(u, v, r)` (what both the log and the controller see); and every
/// command the allocator published, one per stamp of its topic. The
/// thrusters hold the last published command and apply it `dead_time` later.
struct Truth {
    states: Vec<[f64; 4]>,
    errors: Vec<[f64; 3]>,
    published: Vec<[f64; 3]>,
}

/// The navigation filter's error: Gauss–Markov, σ per velocity, 1 s correlation.
const NAV_ERROR: [f64; 3] = [0.01, 0.01, 0.002];
const NAV_CORRELATION: f64 = 1.0;

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// The command the allocator publishes at `t`: the open-loop level, or
/// under dynamic positioning forces against the navigation filter's output.
fn command(spec: &FerryLog, t: f64, level: [f64; 3], x: [f64; 4], e: [f64; 3]) -> [f64; 3] {
    if !(spec.closed_loop.0..spec.closed_loop.1).contains(&t) {
        return level;
    }
    let (u, v, r) = (x[0] + e[0], x[1] + e[1], x[2] + e[2]);
    [
        -4000.0 * u,
        -4000.0 * v,
        -6000.0 * r - 2000.0 * wrap(x[3] - 0.3),
    ]
    .map(|f| f.clamp(-3000.0, 3000.0))
}

/// Open-loop levels held 3–12 s, every sign visited, published at the
/// allocator's stamps `publish` (seconds); the thrusters act on the last
/// published command `dead_time` later.
fn simulate(spec: &FerryLog, rng: &mut ChaCha8Rng, publish: &[f64]) -> Truth {
    const RANGE: [f64; 3] = [3000.0, 2500.0, 1500.0];
    let per_grid = (GRID / FINE).round() as usize;
    let n = (spec.seconds / FINE).round() as usize + 1;
    let mut x = [0.5, 0.0, 0.0, 0.3];
    let a = (-FINE / NAV_CORRELATION).exp();
    let b = (1.0 - a * a).sqrt();
    let mut e: [f64; 3] = std::array::from_fn(|i| NAV_ERROR[i] * normal(rng));
    let (mut states, mut errors) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut published = Vec::with_capacity(publish.len());
    let (mut level, mut until) = ([0.0; 3], 0.0);
    let mut acting = 0;
    for k in 0..n {
        let t = k as f64 * FINE;
        if k % per_grid == 0 && t >= until {
            level = std::array::from_fn(|i| RANGE[i] * rng.random_range(-1.0..1.0));
            until = t + rng.random_range(3.0..12.0);
        }
        while published.len() < publish.len() && publish[published.len()] <= t + 1e-9 {
            published.push(command(spec, t, level, x, e));
        }
        while acting < published.len() && publish[acting] <= t - spec.dead_time + 1e-9 {
            acting += 1;
        }
        let force = acting.checked_sub(1).map_or([0.0; 3], |j| published[j]);
        states.push(x);
        errors.push(e);
        e = std::array::from_fn(|i| a * e[i] + b * NAV_ERROR[i] * normal(rng));
        x = rk4(derivative, x, force, FINE);
    }
    Truth {
        states,
        errors,
        published,
    }
}

/// An angle in (−π, π].
pub(crate) fn wrap(a: f64) -> f64 {
    let w = a - 2.0 * PI * (a / (2.0 * PI)).round();
    if w <= -PI { w + 2.0 * PI } else { w }
}

/// Stamps of a topic (seconds from the start) at `rate` Hz with relative
/// jitter `jitter`, the rate redrawn every minute within `rates` when given.
fn stamps(spec: &FerryLog, rng: &mut ChaCha8Rng, rates: (f64, f64), jitter: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let (mut t, mut rate, mut minute) = (0.0, rates.0, -1.0);
    while t <= spec.seconds {
        if (t / 60.0).floor() > minute {
            minute = (t / 60.0).floor();
            rate = if rates.1 > rates.0 {
                rng.random_range(rates.0..rates.1)
            } else {
                rates.0
            };
        }
        out.push(t);
        t += (1.0 + jitter * rng.random_range(-1.0..1.0)) / rate;
    }
    out
}

/// Grid-aligned stamps every `every` seconds (whole milliseconds).
fn aligned_stamps(spec: &FerryLog, every: f64) -> Vec<f64> {
    let n = (spec.seconds / every).floor() as usize;
    (0..=n)
        .map(|k| (k as f64 * every * 1000.0).round() / 1000.0)
        .collect()
}

/// `series` at `t` seconds: linear between fine steps.
fn at<const N: usize>(series: &[[f64; N]], t: f64) -> [f64; N] {
    let s = t / FINE;
    let k = (s.floor() as usize).min(series.len() - 2);
    let w = s - k as f64;
    let (a, b) = (series[k], series[k + 1]);
    std::array::from_fn(|i| a[i] + w * (b[i] - a[i]))
}

/// The truth at `t` seconds.
fn state_at(truth: &Truth, t: f64) -> [f64; 4] {
    at(&truth.states, t)
}

/// `secs,nsecs` of `t` seconds from the start (whole nanoseconds).
pub(crate) fn stamp_columns(t: f64) -> (i64, i64) {
    let ns = (t * 1e9).round() as i64;
    (
        EPOCH_SECONDS + ns.div_euclid(1_000_000_000),
        ns.rem_euclid(1_000_000_000),
    )
}

/// A local time (UTC+2) as the export writes it: the fraction's leading
/// zeros dropped (10:00:01.05 reads 10:00:01.50, after 10:00:01.100): it
/// goes backwards.
fn local_time(t: f64) -> String {
    let ns = (t * 1e9).round() as i64;
    let day = (ns / 1_000_000_000 + 2 * 3600 + 8 * 3600) % 86_400;
    let ms = (ns / 1_000_000) % 1000;
    format!("{}:{:02}:{:02}.{ms}", day / 3600, day / 60 % 60, day % 60)
}

/// The three topics as CSV text.
struct Topics {
    twist: String,
    heading: String,
    tau: String,
}

/// The allocator's stamps: on the grid when aligned, else at 6–41 Hz with
/// two stalls of about a second (no message; the thrusters hold the last).
fn allocator_stamps(spec: &FerryLog, rng: &mut ChaCha8Rng) -> Vec<f64> {
    if spec.aligned {
        return aligned_stamps(spec, GRID);
    }
    let stalled = |t: f64| (300.0..301.0).contains(&t) || (950.0..951.2).contains(&t);
    let mut all = stamps(spec, rng, (6.0, 41.0), 0.3);
    all.retain(|t| !stalled(*t));
    all
}

fn topics(spec: &FerryLog, truth: &Truth, tau_t: &[f64], rng: &mut ChaCha8Rng) -> Topics {
    let (twist_t, heading_t) = if spec.aligned {
        (aligned_stamps(spec, GRID), aligned_stamps(spec, GRID / 2.0))
    } else {
        (
            stamps(spec, rng, (2.0, 7.5), 0.2),
            stamps(spec, rng, (20.0, 20.0), 0.05),
        )
    };
    let mut twist = String::from("secs,nsecs,u,v,r\n");
    for &t in twist_t
        .iter()
        .filter(|t| **t <= spec.hole.0 || **t >= spec.hole.1)
    {
        let (x, e) = (state_at(truth, t), at(&truth.errors, t));
        let (s, n) = stamp_columns(t);
        let (u, v, r) = (x[0] + e[0], x[1] + e[1], x[2] + e[2]);
        let _ = writeln!(twist, "{s},{n},{u},{v},{r}");
    }
    let mut heading = String::from("secs,nsecs,time_local,psi\n");
    for &t in &heading_t {
        let (s, n) = stamp_columns(t);
        let psi = wrap(state_at(truth, t)[3] + 0.003 * normal(rng));
        let _ = writeln!(heading, "{s},{n},{},{psi}", local_time(t));
    }
    let mut tau = String::from("secs,nsecs,Fx,Fy,Mz\n");
    for (&t, f) in tau_t.iter().zip(&truth.published) {
        let (s, n) = stamp_columns(t);
        let _ = writeln!(tau, "{s},{n},{},{},{}", f[0], f[1], f[2]);
    }
    Topics {
        twist,
        heading,
        tau,
    }
}

/// The manifest that reads the topics.
pub const MANIFEST: &str = "# The ferry's run: one CSV per ROS 2 topic (docs/logs.md).
experiment = \"ferry\"

[sources.twist]
file = \"twist.csv\"
time = [\"secs\", \"nsecs\"]

[sources.heading]
file = \"heading.csv\"
time = [\"secs\", \"nsecs\"]

[sources.tau]
file = \"tau.csv\"
time = [\"secs\", \"nsecs\"]

[signals]
u = \"twist:u\"
v = \"twist:v\"
r = \"twist:r\"
psi = \"heading:psi\"
tau_x = \"tau:Fx\"
tau_y = \"tau:Fy\"
tau_n = \"tau:Mz\"
";

/// Writes the log into `dir`: `twist.csv`, `heading.csv`, `tau.csv`,
/// `ferry.toml` and, when aligned, `uniform.csv`.
pub fn write_ferry_log(dir: &Path, spec: &FerryLog) -> std::io::Result<()> {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let publish = allocator_stamps(spec, &mut rng);
    let truth = simulate(spec, &mut rng, &publish);
    let t = topics(spec, &truth, &publish, &mut rng);
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join("twist.csv"), &t.twist)?;
    std::fs::write(dir.join("heading.csv"), &t.heading)?;
    std::fs::write(dir.join("tau.csv"), &t.tau)?;
    std::fs::write(dir.join("ferry.toml"), MANIFEST)?;
    if spec.aligned {
        std::fs::write(dir.join("uniform.csv"), uniform(&t))?;
    }
    Ok(())
}

/// The aligned topics on one grid, split at the velocities' hole: each grid
/// time's samples as the topics hold them.
fn uniform(t: &Topics) -> String {
    let rows = |text: &str| -> Vec<(i64, Vec<String>)> {
        text.lines()
            .skip(1)
            .filter_map(|l| {
                let cells: Vec<&str> = l.split(',').collect();
                let ns = cells.first()?.parse::<i64>().ok()? * 1_000_000_000
                    + cells.get(1)?.parse::<i64>().ok()?;
                Some((ns, cells[2..].iter().map(|c| c.to_string()).collect()))
            })
            .collect()
    };
    let (twist, heading, tau) = (rows(&t.twist), rows(&t.heading), rows(&t.tau));
    let find = |rows: &[(i64, Vec<String>)], ns: i64| {
        rows.binary_search_by_key(&ns, |r| r.0)
            .ok()
            .map(|i| rows[i].1.clone())
    };
    let mut out = String::from("time,experiment,u,v,r,psi,tau_x,tau_y,tau_n\n");
    let mut piece = 1;
    let mut last = twist.first().map_or(0, |r| r.0);
    let start = last;
    for (ns, v) in &twist {
        if ns - last > 500_000_000 {
            piece += 1;
        }
        last = *ns;
        let (Some(h), Some(f)) = (find(&heading, *ns), find(&tau, *ns)) else {
            continue;
        };
        let time = (ns - start) as f64 / 1e9;
        let _ = writeln!(
            out,
            "{time},ferry/{piece},{},{},{},{},{},{},{}",
            v[0], v[1], v[2], h[1], f[0], f[1], f[2]
        );
    }
    out
}

/// The manifest that reads the bag [`write_ferry_bag`] writes: the same
/// signals by `topic.field.path`, the heading from the IMU's quaternion.
pub const BAG_MANIFEST: &str = "# The ferry's run as a ROS 2 bag (docs/logs.md).
experiment = \"ferry\"

[sources.bag]
file = \"ferry.mcap\"

[signals]
u = \"bag:/navigation/twist_body.twist.linear.x\"
v = \"bag:/navigation/twist_body.twist.linear.y\"
r = \"bag:/navigation/twist_body.twist.angular.z\"
psi = { from = \"bag:/imu.orientation\", as = \"yaw\", frame = \"enu\" }
tau_x = \"bag:/allocator/wrench.wrench.force.x\"
tau_y = \"bag:/allocator/wrench.wrench.force.y\"
tau_n = \"bag:/allocator/wrench.wrench.torque.z\"
";

/// A topic file's stamps (ns since the epoch) and value columns.
fn read_topic(path: &Path) -> Result<(Vec<i64>, Vec<Vec<f64>>), DataError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        DataError::new(
            path.display().to_string(),
            e.to_string(),
            "write the log first",
        )
    })?;
    let mut stamps = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let number = |i: usize| cells.get(i).and_then(|c| c.parse::<f64>().ok());
        let (Some(s), Some(n)) = (number(0), number(1)) else {
            continue;
        };
        stamps.push(s as i64 * 1_000_000_000 + n as i64);
        // The heading's file has a text column (local time) before its value.
        let values: Vec<f64> = (2..cells.len()).filter_map(number).collect();
        columns.resize(values.len(), Vec::new());
        for (c, v) in columns.iter_mut().zip(values) {
            c.push(v);
        }
    }
    Ok((stamps, columns))
}

/// Writes the log's three topics, read back from the CSV files in `dir`,
/// as one ROS 2 bag `ferry.mcap` (TwistStamped, Imu, WrenchStamped) with
/// its manifest `ferry-bag.toml`: the same log, as a robot records it.
pub fn write_ferry_bag(dir: &Path) -> Result<(), DataError> {
    let (twist_t, twist) = read_topic(&dir.join("twist.csv"))?;
    let (heading_t, heading) = read_topic(&dir.join("heading.csv"))?;
    let (tau_t, tau) = read_topic(&dir.join("tau.csv"))?;
    let zeros = |n: usize| vec![0.0; n];
    let (nt, nh, nf) = (twist_t.len(), heading_t.len(), tau_t.len());
    let series = [
        TopicSeries {
            topic: "/navigation/twist_body".into(),
            kind: MessageKind::TwistStamped,
            frame_id: "base_link".into(),
            stamps: twist_t,
            columns: vec![
                twist[0].clone(),
                twist[1].clone(),
                zeros(nt),
                zeros(nt),
                zeros(nt),
                twist[2].clone(),
            ],
        },
        TopicSeries {
            topic: "/imu".into(),
            kind: MessageKind::Imu,
            frame_id: "imu_link".into(),
            stamps: heading_t,
            // REP 103: the orientation in ENU, its yaw from east
            // counter-clockwise, 90° − the heading.
            columns: std::iter::once(heading[0].iter().map(|psi| wrap(PI / 2.0 - psi)).collect())
                .chain((0..6).map(|_| zeros(nh)))
                .collect(),
        },
        TopicSeries {
            topic: "/allocator/wrench".into(),
            kind: MessageKind::WrenchStamped,
            frame_id: "base_link".into(),
            stamps: tau_t,
            columns: vec![
                tau[0].clone(),
                tau[1].clone(),
                zeros(nf),
                zeros(nf),
                zeros(nf),
                tau[2].clone(),
            ],
        },
    ];
    write_bag(&dir.join("ferry.mcap"), &series)?;
    std::fs::write(dir.join("ferry-bag.toml"), BAG_MANIFEST)
        .map_err(|e| DataError::new(dir.display().to_string(), e.to_string(), "check the folder"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_local_time_goes_backwards_and_the_stamps_do_not() {
        assert_eq!(local_time(1.05), "10:00:01.50");
        assert_eq!(local_time(1.5), "10:00:01.500");
        assert_eq!(stamp_columns(1.05), (EPOCH_SECONDS + 1, 50_000_000));
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-12 && (wrap(-PI) - PI).abs() < 1e-12);
    }
}
