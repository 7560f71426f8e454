//! Units a `data { }` entry may declare for a column (`r in deg/s`), and the
//! factor that converts a logged value into the model's base unit on load.
//!
//! Base units: rad (angles), rad/s (angular rates), m/s (speeds), rev/s
//! (rotation rates of shafts and propellers), s (time). A model's parameters
//! are estimated in these units, so declaring the unit of a column never
//! changes what a parameter means.

/// What a unit measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Angles (base: rad).
    Angle,
    /// Angular rates (base: rad/s).
    AngularRate,
    /// Speeds (base: m/s).
    Speed,
    /// Shaft or propeller rotation rates (base: rev/s).
    RotationRate,
    /// Time stamps (base: s).
    Time,
}

impl Kind {
    /// The kind in words, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Angle => "an angle",
            Kind::AngularRate => "an angular rate",
            Kind::Speed => "a speed",
            Kind::RotationRate => "a rotation rate",
            Kind::Time => "a time",
        }
    }
    /// The base unit values are converted to.
    pub fn base(self) -> &'static str {
        match self {
            Kind::Angle => "rad",
            Kind::AngularRate => "rad/s",
            Kind::Speed => "m/s",
            Kind::RotationRate => "rev/s",
            Kind::Time => "s",
        }
    }
}

/// Every accepted unit: (name as written, kind, factor to the base unit).
pub const UNITS: [(&str, Kind, f64); 13] = [
    ("rad", Kind::Angle, 1.0),
    ("deg", Kind::Angle, std::f64::consts::PI / 180.0),
    ("rad/s", Kind::AngularRate, 1.0),
    ("deg/s", Kind::AngularRate, std::f64::consts::PI / 180.0),
    ("m/s", Kind::Speed, 1.0),
    // One knot is one nautical mile (1852 m) per hour.
    ("knots", Kind::Speed, 1852.0 / 3600.0),
    ("kn", Kind::Speed, 1852.0 / 3600.0),
    ("km/h", Kind::Speed, 1000.0 / 3600.0),
    ("rps", Kind::RotationRate, 1.0),
    ("Hz", Kind::RotationRate, 1.0),
    ("rpm", Kind::RotationRate, 1.0 / 60.0),
    ("s", Kind::Time, 1.0),
    ("ms", Kind::Time, 1e-3),
];

/// A unit by the name written in the model (exact spelling).
pub fn unit(name: &str) -> Option<(Kind, f64)> {
    UNITS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, k, f)| (*k, *f))
}

/// The accepted units of some kinds, as a list for a hint (`deg, rad`).
pub fn names_of(kinds: &[Kind]) -> String {
    UNITS
        .iter()
        .filter(|(_, k, _)| kinds.contains(k))
        .map(|(n, _, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The factor of a unit (1 for an unknown one; the compiler rejects those).
pub fn factor(name: &str) -> f64 {
    unit(name).map_or(1.0, |(_, f)| f)
}

/// The factor of the unit a model's `data { }` declares for `signal` (1
/// when it declares none).
pub fn factor_of(ir: &crate::ir::Ir, signal: &str) -> f64 {
    ir.data_units.get(signal).map_or(1.0, |u| factor(u))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_reach_the_base_units() {
        let to_base = |u: &str, v: f64| v * factor(u);
        assert_eq!(to_base("deg", 180.0), std::f64::consts::PI);
        assert_eq!(to_base("deg", 35.0), 35.0f64.to_radians());
        assert_eq!(to_base("rpm", 120.0), 2.0);
        assert_eq!(to_base("km/h", 36.0), 10.0);
        assert!((to_base("knots", 1.0) - 0.514_444).abs() < 1e-6);
        assert_eq!(to_base("ms", 500.0), 0.5);
        assert_eq!(unit("Hz"), unit("rps"));
        assert_eq!(unit("DEG"), None);
        assert_eq!(names_of(&[Kind::Angle]), "rad, deg");
    }
}
