//! The plan file: what an engineer knows before the trial (TOML or JSON,
//! `docs/design.md`), read into [`Conditions`] against a model. Everything
//! the file leaves out gets a stated default ([`Conditions::assumptions`]),
//! except an actuator's range: the design is bounded by it and no default
//! would be honest.

use crate::error::DesignError;
use leeway_structure::ir::{Ir, Rotation};
use serde::Deserialize;
use std::collections::BTreeMap;

/// The plan file as written.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanFile {
    /// Sample time of the trial's log, s (default: the model's `step`).
    pub step: Option<f64>,
    /// θ to design for, by name (default: the model's `nominal { }`).
    #[serde(default)]
    pub nominal: BTreeMap<String, f64>,
    /// Limits per input.
    #[serde(default)]
    pub inputs: BTreeMap<String, InputLimits>,
    /// Expected statistics per medium.
    #[serde(default)]
    pub disturbances: BTreeMap<String, MediumPlan>,
    /// Measurement noise std per state and for the heading.
    #[serde(default)]
    pub noise: BTreeMap<String, f64>,
    /// Time at sea.
    pub budget: Option<Budget>,
    /// The excitation family (`auto`, the default, chooses by predicted information).
    pub excitation: Option<String>,
    /// θ's prior uncertainty: each parameter's standard deviation as a
    /// fraction of its nominal value (default 0: the nominal θ is the truth).
    pub prior: Option<f64>,
    /// The trial area.
    pub area: Option<Area>,
}

/// The sea room the skipper gives.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Area {
    /// Metres from the start a run may go.
    pub radius: Option<f64>,
    /// A box: metres north of the start, `[low, high]` (south negative).
    #[serde(default, deserialize_with = "optional_pair")]
    pub north: Option<[f64; 2]>,
    /// A box: metres east of the start, `[low, high]` (west negative).
    #[serde(default, deserialize_with = "optional_pair")]
    pub east: Option<[f64; 2]>,
}

/// A box-shaped trial area around the start, m (a side not given is
/// unbounded: a channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaBox {
    /// `[low, high]` north of the start.
    pub north: [f64; 2],
    /// `[low, high]` east of the start.
    pub east: [f64; 2],
}

/// An actuator's limits.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputLimits {
    /// `[low, high]` (exactly two numbers), in `unit`.
    #[serde(deserialize_with = "pair")]
    pub range: [f64; 2],
    /// Largest change per second (optional), in `unit` per second.
    pub rate: Option<f64>,
    /// The unit of `range` and `rate`: by default the unit the model's
    /// `data { }` reads the input in (`in deg`), else the model's own.
    pub unit: Option<String>,
}

/// One number for every component, or one per component.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum PerComponent {
    /// The same value for each component.
    One(f64),
    /// In the medium's component order.
    Each(Vec<f64>),
}

/// A medium's expected statistics.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumPlan {
    /// Mean per component (earth frame for an earth-fixed medium).
    pub mean: Option<PerComponent>,
    /// Standard deviation about the mean, per component.
    pub std: Option<PerComponent>,
    /// Correlation time, s (0: white from sample to sample).
    pub correlation_time: Option<f64>,
    /// How far the true mean may be from `mean` (a speed, any direction).
    pub mean_uncertainty: Option<f64>,
    /// Sensor noise std of a measured medium, per component.
    pub sensor_noise: Option<PerComponent>,
}

/// The time at sea.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Budget {
    /// Total time at sea, s, shared equally by the experiments.
    pub time: Option<f64>,
    /// Samples per experiment.
    pub samples: Option<usize>,
}

/// An actuator's limits in samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Lowest value.
    pub low: f64,
    /// Highest value.
    pub high: f64,
    /// Largest change per sample (`∞` without a rate limit).
    pub per_sample: f64,
}

impl Limits {
    /// `high − low`.
    pub fn span(&self) -> f64 {
        self.high - self.low
    }
}

/// The excitation families a design can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    /// Smoothed pulses of random width and amplitude (the paper's §V input).
    Pulses,
    /// A pseudo-random binary sequence with a random hold time.
    Prbs,
    /// A sum of sines over the craft's band, random phases.
    Multisine,
    /// Square waves of incommensurate periods per input.
    Zigzag,
}

impl Family {
    /// Every family, in the order they are tried.
    pub const ALL: [Family; 4] = [
        Family::Pulses,
        Family::Prbs,
        Family::Multisine,
        Family::Zigzag,
    ];
    /// `pulses`, `prbs`, ...
    pub fn name(self) -> &'static str {
        match self {
            Family::Pulses => "pulses",
            Family::Prbs => "prbs",
            Family::Multisine => "multisine",
            Family::Zigzag => "zigzag",
        }
    }
}

/// The plan read against a model: one value per input, component and state.
#[derive(Clone, Debug)]
pub struct Conditions {
    /// θ designed for.
    pub theta: Vec<f64>,
    /// Sample time, s.
    pub h: f64,
    /// Per input.
    pub limits: Vec<Limits>,
    /// Mean per component.
    pub mean: Vec<f64>,
    /// Std per component.
    pub std: Vec<f64>,
    /// Correlation time per component, s.
    pub correlation_time: Vec<f64>,
    /// Uncertainty of the mean per component (the medium's speed bound).
    pub uncertainty: Vec<f64>,
    /// Sensor noise per component (measured media).
    pub sensor_noise: Vec<f64>,
    /// Measurement noise per state; `None`: 1 % of the planned excursion
    /// (decided once the nominal trajectory is known, and stated).
    pub state_noise: Vec<Option<f64>>,
    /// Heading noise, rad (`None` as for states).
    pub heading_noise: Option<f64>,
    /// Samples per experiment, or the total time to share.
    pub budget: BudgetRule,
    /// A family the plan insists on.
    pub family: Option<Family>,
    /// θ's prior uncertainty, a fraction of each nominal value (0: known).
    pub prior: f64,
    /// Metres from the start a run's nominal track may go (`None`: no limit given).
    pub area_radius: Option<f64>,
    /// The box a run's nominal track must stay in (`None`: none given).
    pub area_box: Option<AreaBox>,
    /// What the plan did not say and the design assumed, in words.
    pub assumptions: Vec<String>,
}

pub use crate::bounds::BudgetRule;

/// The most bytes of a plan file: 1 MiB, as a model's source. The front
/// ends read no more of a file (a pipe, `/dev/zero`) than this and a byte.
pub const MAX_PLAN_BYTES: u64 = 1 << 20;

/// The largest prior uncertainty a plan may give: at 2.5 standard
/// deviations a parameter keeps its sign below 0.4.
pub const MAX_PRIOR: f64 = 0.35;

/// The default time per experiment when the plan gives no budget, s.
pub const DEFAULT_SECONDS: f64 = 600.0;
pub use crate::bounds::SAMPLES;

/// `range = [low, high]`: exactly two numbers (a fixed-size array would
/// drop a third in TOML).
fn optional_pair<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    pair(d).map(Some)
}

fn pair<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    let values = Vec::<f64>::deserialize(d)?;
    match values[..] {
        [low, high] => Ok([low, high]),
        _ => Err(serde::de::Error::custom(format!(
            "a range is [low, high], two numbers; this one has {}",
            values.len()
        ))),
    }
}

/// Whether the text is read as JSON: `json`, or text starting with `{`.
pub fn is_json(text: &str, json: bool) -> bool {
    json || text.trim_start().starts_with('{')
}

/// Reads a plan file's text: JSON when `json` (or when the text starts with
/// `{`), TOML otherwise. Syntax errors carry the line and column; a key
/// given twice is refused in either (TOML by its grammar, JSON here, at
/// every level).
pub fn parse(text: &str, json: bool) -> Result<PlanFile, DesignError> {
    if is_json(text, json) {
        let located = |e: serde_json::Error| {
            let (line, column) = json_place(text, e.line(), e.column());
            DesignError::plan(
                format!("{e}"),
                "the plan is JSON (docs/design.md lists its fields)",
            )
            .at(line, column)
        };
        let mut scan = serde_json::Deserializer::from_str(text);
        serde::de::DeserializeSeed::deserialize(Scan::default(), &mut scan).map_err(located)?;
        serde_json::from_str(text).map_err(located)
    } else {
        toml::from_str(text).map_err(|e| {
            let at = e.span().map(|s| line_col(text, s.start));
            let message = e.message().to_string();
            let err = DesignError::plan(
                message,
                "the plan is TOML (docs/design.md lists its fields)",
            );
            match at {
                Some((l, c)) => err.at(l, c),
                None => err,
            }
        })
    }
}

/// `e` at the line and column of its key (`budget.time`) in the plan's
/// text, when it names one the text gives and is not located yet; `e`
/// otherwise.
pub fn locate(e: DesignError, text: &str, json: bool) -> DesignError {
    let Some(key) = e.key.clone().filter(|_| e.line.is_none()) else {
        return e;
    };
    let at = if is_json(text, json) {
        let mut de = serde_json::Deserializer::from_str(text);
        let scan = Scan {
            path: "",
            target: Some(&key),
        };
        match serde::de::DeserializeSeed::deserialize(scan, &mut de) {
            Err(found) if found.to_string().starts_with(FOUND) => {
                Some((found.line(), found.column()))
            }
            _ => None,
        }
    } else {
        toml::de::DeTable::parse(text)
            .ok()
            .and_then(|table| toml_find(table.get_ref(), &key))
            .map(|byte| line_col(text, byte))
    };
    match at {
        Some((l, c)) => e.at(l, c),
        None => e,
    }
}

/// serde_json's line and column as an editor shows them: its column 0
/// (a line end read, as in a string broken by one) is the previous line's
/// end, where the line end is.
fn json_place(text: &str, line: usize, column: usize) -> (usize, usize) {
    match (line, column) {
        (2.., 0) => {
            let previous = text.split('\n').nth(line - 2).unwrap_or("");
            (line - 1, previous.chars().count() + 1)
        }
        _ => (line.max(1), column.max(1)),
    }
}

/// Where the value at the dotted `key` starts in a TOML table: a name
/// may hold dots itself (`inputs."a.b"`), so each key of the table that
/// begins the rest is tried.
fn toml_find(table: &toml::de::DeTable<'_>, key: &str) -> Option<usize> {
    table.iter().find_map(|(k, v)| {
        let k: &str = k.get_ref();
        if key == k {
            return Some(v.span().start);
        }
        let rest = key.strip_prefix(k)?.strip_prefix('.')?;
        toml_find(v.get_ref().as_table()?, rest)
    })
}

/// The message that marks the key [`locate`] looks for.
const FOUND: &str = "\u{0}found";

/// A walk over a JSON value that refuses a key given twice in any object
/// (serde_json keeps the last), or stops at the key `target` with [`FOUND`]
/// (serde_json's error then says where it is).
#[derive(Clone, Copy, Default)]
struct Scan<'a> {
    /// Where the walk is, `inputs.f.` (empty at the top).
    path: &'a str,
    /// The dotted key sought, from here down (a name may hold dots).
    target: Option<&'a str>,
}

impl<'de> serde::de::DeserializeSeed<'de> for Scan<'_> {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for Scan<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let inner = Scan {
            target: None,
            ..self
        };
        while seq.next_element_seed(inner)?.is_some() {}
        Ok(())
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        use serde::de::Error;
        let mut seen = std::collections::BTreeSet::new();
        while let Some(key) = map.next_key::<String>()? {
            let target = match self.target {
                Some(sought) if sought == key => return Err(A::Error::custom(FOUND)),
                Some(sought) => sought
                    .strip_prefix(key.as_str())
                    .and_then(|rest| rest.strip_prefix('.')),
                None => None,
            };
            let path = format!("{}{key}", self.path);
            if !seen.insert(key) {
                return Err(A::Error::custom(format!(
                    "`{path}` is given twice (a key is given once)"
                )));
            }
            let below = format!("{path}.");
            map.next_value_seed(Scan {
                path: &below,
                target,
            })?;
        }
        Ok(())
    }
}

fn line_col(text: &str, byte: usize) -> (usize, usize) {
    let before = &text[..byte.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

impl PlanFile {
    /// The conditions for `ir`, every name checked and every number bounded.
    pub fn conditions(&self, ir: &Ir) -> Result<Conditions, DesignError> {
        if matches!(ir.rotation, Rotation::Measured { .. }) {
            return Err(DesignError::cannot(
                "the rotation is measured entry by entry (`rotation { }`): a design cannot predict R along a trial",
                "give the craft a heading (`heading psi integrates r`) if it turns in the plane, or design its runs by hand and check them with `leeway check --pattern`",
            ));
        }
        let mut assumptions = Vec::new();
        let theta = self.theta(ir)?;
        let h = self.step(ir, &mut assumptions)?;
        let limits = self.limits(ir, h)?;
        let media = self.media(ir, &mut assumptions)?;
        let (state_noise, heading_noise) = self.noise(ir)?;
        let budget = self.budget(&mut assumptions)?;
        let prior = self.prior(&mut assumptions)?;
        let area_radius = match self.area.as_ref().and_then(|a| a.radius) {
            Some(r) if r.is_finite() && r > 0.0 => Some(r),
            Some(r) => {
                return Err(DesignError::plan(
                    format!("area.radius = {r} is not a distance"),
                    "give the metres from the start the craft may go",
                )
                .key("area.radius"));
            }
            None => None,
        };
        let area_box = self.area_box()?;
        let family = match self.excitation.as_deref() {
            None | Some("auto") => None,
            Some(name) => Some(
                Family::ALL
                    .into_iter()
                    .find(|f| f.name() == name)
                    .ok_or_else(|| {
                        DesignError::plan(
                            format!("excitation = \"{name}\" is not a family"),
                            "use auto, pulses, prbs, multisine or zigzag",
                        )
                        .key("excitation")
                    })?,
            ),
        };
        Ok(Conditions {
            theta,
            h,
            limits,
            mean: media.mean,
            std: media.std,
            correlation_time: media.time,
            uncertainty: media.uncertainty,
            sensor_noise: media.sensor,
            state_noise,
            heading_noise,
            budget,
            family,
            prior,
            area_radius,
            area_box,
            assumptions,
        })
    }

    /// `[area] north`, `east`: each `[low, high]` metres with the start
    /// (0) inside.
    fn area_box(&self) -> Result<Option<AreaBox>, DesignError> {
        let Some(area) = self.area.as_ref() else {
            return Ok(None);
        };
        let side = |key: &str, range: Option<[f64; 2]>| -> Result<[f64; 2], DesignError> {
            let Some([low, high]) = range else {
                return Ok([f64::NEG_INFINITY, f64::INFINITY]);
            };
            if !(low.is_finite() && high.is_finite() && low <= 0.0 && 0.0 <= high && low < high) {
                return Err(DesignError::plan(
                    format!("area.{key} = [{low}, {high}] does not hold the start"),
                    if key == "north" {
                        "give [low, high] metres north of the start, low ≤ 0 ≤ high (south negative: [-200, 400])"
                    } else {
                        "give [low, high] metres east of the start, low ≤ 0 ≤ high (west negative: [-200, 400])"
                    },
                )
                .key(&format!("area.{key}")));
            }
            Ok([low, high])
        };
        if area.north.is_none() && area.east.is_none() {
            return Ok(None);
        }
        Ok(Some(AreaBox {
            north: side("north", area.north)?,
            east: side("east", area.east)?,
        }))
    }

    /// θ's prior uncertainty: 0 to [`MAX_PRIOR`] of each nominal value.
    fn prior(&self, assumptions: &mut Vec<String>) -> Result<f64, DesignError> {
        match self.prior {
            None => {
                assumptions.push(
                    "θ known: the nominal θ is taken as the truth (the plan gives no `prior`)".into(),
                );
                Ok(0.0)
            }
            Some(p) if p.is_finite() && (0.0..=MAX_PRIOR).contains(&p) => Ok(p),
            Some(p) => Err(DesignError::plan(
                format!("prior = {p} is not a fraction from 0 to {MAX_PRIOR}"),
                "give θ's uncertainty as a fraction of each nominal value (0.3 for ±30 %); beyond a third a parameter's sign is in doubt and no margin can be designed for it",
            )
            .key("prior")),
        }
    }

    fn theta(&self, ir: &Ir) -> Result<Vec<f64>, DesignError> {
        let mut theta: Vec<f64> = ir.parameters.iter().map(|p| p.nominal).collect();
        for (name, value) in &self.nominal {
            let i = ir
                .parameters
                .iter()
                .position(|p| &p.name == name)
                .ok_or_else(|| unknown("nominal", name, ir.parameters.iter().map(|p| &p.name)))?;
            finite(&format!("nominal.{name}"), *value)?;
            theta[i] = *value;
        }
        Ok(theta)
    }

    fn step(&self, ir: &Ir, assumptions: &mut Vec<String>) -> Result<f64, DesignError> {
        let h = match (self.step, ir.step) {
            (Some(h), _) => h,
            (None, Some(h)) => {
                assumptions.push(format!("sample time: the model's step, {h} s"));
                h
            }
            (None, None) => {
                return Err(DesignError::plan(
                    "the model declares no `step` and the plan gives none".to_string(),
                    "add `step = 0.1` (the trial log's sample time, s) to the plan",
                ));
            }
        };
        if !(h.is_finite() && h > 0.0 && h <= 3600.0) {
            return Err(DesignError::plan(
                format!("step = {h} is not a sample time"),
                "give a positive sample time in seconds, at most 3600",
            )
            .key("step"));
        }
        Ok(h)
    }

    fn limits(&self, ir: &Ir, h: f64) -> Result<Vec<Limits>, DesignError> {
        for name in self.inputs.keys() {
            if !ir.inputs.contains(name) {
                return Err(unknown("inputs", name, ir.inputs.iter()));
            }
        }
        ir.inputs
            .iter()
            .map(|name| {
                let l = self.inputs.get(name).ok_or_else(|| {
                    DesignError::plan(
                        format!("the plan gives no range for the input `{name}`"),
                        &format!(
                            "an actuator's range bounds the design: add `[inputs.{name}]` with `range = [low, high]`"
                        ),
                    )
                })?;
                let [low, high] = l.range;
                if !(low.is_finite() && high.is_finite() && low < high) {
                    return Err(DesignError::plan(
                        format!("inputs.{name}.range = [{low}, {high}] is not a range"),
                        "give [low, high] with low < high, both finite",
                    )
                    .key(&format!("inputs.{name}.range")));
                }
                let (unit, factor, angle) = input_unit(ir, name, l.unit.as_deref())?;
                let (low, high) = (low * factor, high * factor);
                if angle && low.abs().max(high.abs()) > std::f64::consts::PI {
                    return Err(absurd_angle(ir, name, l.range, &unit));
                }
                let per_sample = match l.rate {
                    None => f64::INFINITY,
                    Some(r) if r.is_finite() && r > 0.0 => r * factor * h,
                    Some(r) => {
                        return Err(DesignError::plan(
                            format!("inputs.{name}.rate = {r} is not a rate"),
                            "give the largest change per second, positive",
                        )
                        .key(&format!("inputs.{name}.rate")));
                    }
                };
                Ok(Limits {
                    low,
                    high,
                    per_sample,
                })
            })
            .collect()
    }

    /// Noise per state and for the heading, each in its signal's data unit
    /// (`noise.r` in deg/s for `r in deg/s`), returned in the model's.
    fn noise(&self, ir: &Ir) -> Result<(Vec<Option<f64>>, Option<f64>), DesignError> {
        let heading = match &ir.rotation {
            Rotation::Planar { heading, .. } => Some(heading.as_str()),
            _ => None,
        };
        for (name, value) in &self.noise {
            if !ir.states.contains(name) && Some(name.as_str()) != heading {
                return Err(unknown(
                    "noise",
                    name,
                    ir.states.iter().map(String::as_str).chain(heading),
                ));
            }
            non_negative(&format!("noise.{name}"), *value)?;
        }
        let base = |name: &str| {
            self.noise
                .get(name)
                .map(|v| v * leeway_structure::units::factor_of(ir, name))
        };
        let states = ir.states.iter().map(|s| base(s)).collect();
        Ok((states, heading.and_then(base)))
    }

    fn budget(&self, assumptions: &mut Vec<String>) -> Result<BudgetRule, DesignError> {
        let b = self.budget.clone().unwrap_or_default();
        match (b.time, b.samples) {
            (Some(_), Some(_)) => Err(DesignError::plan(
                "the budget gives both `time` and `samples`".to_string(),
                "give the total time at sea (`time`, s) or the samples per experiment (`samples`), not both",
            )
            .key("budget.samples")),
            (Some(t), None) if t.is_finite() && t > 0.0 => Ok(BudgetRule::Time(t)),
            (Some(t), None) => Err(DesignError::plan(
                format!("budget.time = {t} is not a duration"),
                "give the total time at sea in seconds",
            )
            .key("budget.time")),
            (None, Some(n)) if (SAMPLES.0..=SAMPLES.1).contains(&n) => Ok(BudgetRule::Samples(n)),
            (None, Some(n)) => Err(DesignError::plan(
                format!(
                    "budget.samples = {n} is not in {}..={}",
                    SAMPLES.0, SAMPLES.1
                ),
                "give the samples per experiment",
            )
            .key("budget.samples")),
            (None, None) => {
                assumptions.push(format!(
                    "budget: {DEFAULT_SECONDS} s per experiment (the plan gives none)"
                ));
                Ok(BudgetRule::Each(DEFAULT_SECONDS))
            }
        }
    }
}

/// The unit an input's plan values are in, its factor to the model's unit,
/// and whether the input is an angle. `given` (the plan's `unit`) must be
/// of the kind the model's `data { }` declares for the input.
fn input_unit(
    ir: &Ir,
    name: &str,
    given: Option<&str>,
) -> Result<(String, f64, bool), DesignError> {
    use leeway_structure::units::{Kind, names_of, unit};
    let declared = ir
        .data_units
        .get(name)
        .and_then(|u| Some((u.clone(), unit(u)?)));
    let key = format!("inputs.{name}.unit");
    match (given, declared) {
        (None, None) => Ok(("the model's unit".into(), 1.0, false)),
        (None, Some((u, (kind, f)))) => Ok((u, f, kind == Kind::Angle)),
        (Some(g), None) => Err(DesignError::plan(
            format!("inputs.{name}.unit = \"{g}\": the model declares no unit for `{name}`"),
            &format!(
                "give the range in the model's own unit and leave out `unit`, or declare the log's unit in the model's data {{ }} block (`{name} = \"column\" in {g}`)"
            ),
        )
        .key(&key)),
        (Some(g), Some((u, (kind, _)))) => match unit(g) {
            Some((k, f)) if k == kind => Ok((g.to_string(), f, kind == Kind::Angle)),
            _ => Err(DesignError::plan(
                format!(
                    "inputs.{name}.unit = \"{g}\" is not {} (the model reads `{name}` in {u})",
                    kind.name()
                ),
                &format!("give one of {}", names_of(&[kind])),
            )
            .key(&key)),
        },
    }
}

/// The error for an angle range beyond ±π rad in the model's unit: most
/// likely degrees read as radians.
fn absurd_angle(ir: &Ir, name: &str, range: [f64; 2], unit: &str) -> DesignError {
    let declared = ir.data_units.get(name).map_or("rad", String::as_str);
    DesignError::plan(
        format!(
            "inputs.{name}.range = [{}, {}] {unit} is beyond ±180° for the angle `{name}`",
            range[0], range[1]
        ),
        &format!(
            "plan values are in the unit the model's data {{ }} reads `{name}` in ({declared}): give degrees with `unit = \"deg\"`, radians with `unit = \"rad\"`"
        ),
    )
    .key(&format!("inputs.{name}.range"))
}

/// Per-component statistics of every medium.
struct Media {
    mean: Vec<f64>,
    std: Vec<f64>,
    time: Vec<f64>,
    uncertainty: Vec<f64>,
    sensor: Vec<f64>,
}

impl PlanFile {
    fn media(&self, ir: &Ir, assumptions: &mut Vec<String>) -> Result<Media, DesignError> {
        for name in self.disturbances.keys() {
            if !ir.disturbances.iter().any(|d| &d.name == name) {
                return Err(unknown(
                    "disturbances",
                    name,
                    ir.disturbances.iter().map(|d| &d.name),
                ));
            }
        }
        let n = ir.components.len();
        let mut m = Media {
            mean: vec![0.0; n],
            std: vec![0.0; n],
            time: vec![0.0; n],
            uncertainty: vec![0.0; n],
            sensor: vec![0.0; n],
        };
        for d in &ir.disturbances {
            let Some(p) = self.disturbances.get(&d.name) else {
                assumptions.push(format!(
                    "{}: calm (mean 0, std 0; the plan gives no statistics)",
                    d.name
                ));
                continue;
            };
            let key = |field: &str| format!("disturbances.{}.{field}", d.name);
            let k = d.components.len();
            let fill = |field: &str, v: &Option<PerComponent>, out: &mut Vec<f64>, signed: bool| {
                let values = each(&key(field), v, k)?;
                for (c, x) in d.components.iter().zip(values) {
                    if signed {
                        finite(&key(field), x)?
                    } else {
                        non_negative(&key(field), x)?
                    }
                    out[*c] = x;
                }
                Ok::<(), DesignError>(())
            };
            fill("mean", &p.mean, &mut m.mean, true)?;
            fill("std", &p.std, &mut m.std, false)?;
            if p.sensor_noise.is_some() && !d.measured {
                return Err(DesignError::plan(
                    format!(
                        "{} has a sensor_noise but the model does not measure {}",
                        key("sensor_noise"),
                        d.name
                    ),
                    "sensor noise belongs to a medium declared `measured`; give the states' noise under [noise]",
                )
                .key(&key("sensor_noise")));
            }
            if p.correlation_time.is_some()
                && each(&key("std"), &p.std, k)?.iter().all(|s| *s == 0.0)
            {
                return Err(DesignError::plan(
                    format!(
                        "{} is given but {} does not vary about its mean (no std)",
                        key("correlation_time"),
                        d.name
                    ),
                    "a correlation time is that of the variation about the mean: give std too, or leave correlation_time out",
                )
                .key(&key("correlation_time")));
            }
            fill("sensor_noise", &p.sensor_noise, &mut m.sensor, false)?;
            let t = p.correlation_time.unwrap_or(0.0);
            non_negative(&key("correlation_time"), t)?;
            let u = p.mean_uncertainty.unwrap_or(0.0);
            non_negative(&key("mean_uncertainty"), u)?;
            for c in &d.components {
                m.time[*c] = t;
                m.uncertainty[*c] = u;
            }
            if p.correlation_time.is_none() && p.std.is_some() {
                assumptions.push(format!(
                    "{}: white from sample to sample (no correlation_time)",
                    d.name
                ));
            }
        }
        Ok(m)
    }
}

fn each(key: &str, v: &Option<PerComponent>, k: usize) -> Result<Vec<f64>, DesignError> {
    match v {
        None => Ok(vec![0.0; k]),
        Some(PerComponent::One(x)) => Ok(vec![*x; k]),
        Some(PerComponent::Each(xs)) if xs.len() == k => Ok(xs.clone()),
        Some(PerComponent::Each(xs)) => Err(DesignError::plan(
            format!(
                "{key} has {} values; the medium has {k} components",
                xs.len()
            ),
            "give one number for every component, or one per component in the model's order",
        )
        .key(key)),
    }
}

fn finite(key: &str, x: f64) -> Result<(), DesignError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(DesignError::plan(
            format!("{key} = {x} is not a number"),
            "give a finite number",
        )
        .key(key))
    }
}

fn non_negative(key: &str, x: f64) -> Result<(), DesignError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(DesignError::plan(
            format!("{key} = {x} is not a non-negative number"),
            "a standard deviation, time or bound is ≥ 0 and finite",
        )
        .key(key))
    }
}

fn unknown<'a>(
    table: &str,
    name: &str,
    known: impl Iterator<Item = impl AsRef<str> + 'a>,
) -> DesignError {
    let known: Vec<String> = known.map(|s| s.as_ref().to_string()).collect();
    DesignError::plan(
        format!(
            "{table}.{name}: the model has no {} named `{name}`",
            singular(table)
        ),
        &format!("the model's: {}", known.join(", ")),
    )
    .key(&format!("{table}.{name}"))
}

fn singular(table: &str) -> &str {
    match table {
        "inputs" => "input",
        "disturbances" => "disturbance",
        "nominal" => "parameter",
        _ => "state or heading",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_and_json_read_alike() {
        let t = parse(
            "step = 0.5\n[inputs.f]\nrange = [-1, 2]\nrate = 4\n[disturbances.current]\nmean = [0.1, 0.2]\nstd = 0.05\n",
            false,
        )
        .expect("reads");
        let j = parse(
            r#"{"step": 0.5, "inputs": {"f": {"range": [-1, 2], "rate": 4}}, "disturbances": {"current": {"mean": [0.1, 0.2], "std": 0.05}}}"#,
            true,
        )
        .expect("reads");
        assert_eq!(format!("{t:?}"), format!("{j:?}"));
    }

    #[test]
    fn a_name_holding_a_dot_is_located() {
        for (text, json, at) in [
            ("[inputs.\"th.rust\"]\nrange = [0, 1]\n", false, (1, 1)),
            ("[inputs]\n\"th.rust\".range = [0, 1]\n", false, (2, 1)),
            (
                "{\"inputs\": {\n\"th.rust\": {\"range\": [0, 1]}}}",
                true,
                (2, 9),
            ),
        ] {
            let e = DesignError::plan("unknown".into(), "").key("inputs.th.rust");
            let e = locate(e, text, json);
            assert_eq!((e.line, e.column), (Some(at.0), Some(at.1)), "{text}");
        }
    }

    #[test]
    fn a_json_string_broken_by_a_line_end_is_located_at_that_line_end() {
        let e = parse("{\"budget\": {\"t\nime\": 1800}}", true).expect_err("refused");
        assert_eq!((e.line, e.column), (Some(1), Some(15)), "{e:?}");
    }

    #[test]
    fn a_json_plan_reads_its_numbers_to_their_bits() {
        // serde_json's default parser reads this one an ulp off.
        let text =
            r#"{"nominal": {"Y_v": -9.285898019307274000e-148, "X_u": 2.2250738585072011e-308}}"#;
        let p = parse(text, true).expect("reads");
        let want = |s: &str| s.parse::<f64>().map(f64::to_bits).ok();
        assert_eq!(
            p.nominal.get("Y_v").map(|x| x.to_bits()),
            want("-9.285898019307274e-148")
        );
        assert_eq!(
            p.nominal.get("X_u").map(|x| x.to_bits()),
            want("2.2250738585072011e-308")
        );
    }

    #[test]
    fn syntax_errors_are_located() {
        let e = parse("step = 0.5\n[inputs.f]\nrange = [-1, \n", false).expect_err("refused");
        assert_eq!(e.line, Some(3), "{e:?}");
        let e = parse("{\"step\": 0.5,\n \"colour\": 1}", true).expect_err("refused");
        assert_eq!(e.line, Some(2), "{e:?}");
        assert!(e.message.contains("colour"), "{e:?}");
    }
}
