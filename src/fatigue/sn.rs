//! S-N curves of DNV-RP-C203 (DNVGL-RP-C203, edition April 2016), §2.4: every detail class
//! B1 … W3 in air (Table 2-1), in seawater with cathodic protection (Table 2-2) and in seawater
//! under free corrosion (Table 2-3), with the thickness correction of §2.4.3.
//!
//! The curve (DNV-RP-C203 eq. 2.4.1, with the thickness correction eq. 2.4.3):
//!
//! log N = log ā − m · log(Δσ · (t_eff/t_ref)^k),  t_eff = max(t, t_ref),
//!
//! N the number of cycles to failure at the stress range Δσ (MPa), m the negative inverse slope,
//! log ā the intercept of the log N axis. In air and in seawater with cathodic protection the
//! curve has two slopes, m₁ for high ranges and m₂ = 5 below the knee (N = 10⁷ in air, 10⁶ in
//! seawater with CP); under free corrosion it has one slope, m = 3, and no knee.
//!
//! **The knee.** The tables give log ā₁ and log ā₂ rounded to three decimals, so the two
//! segments meet at N = 10⁷ (10⁶) only to that rounding. [`SnCurve`] switches from one segment
//! to the other where they intersect, Δσ* = 10^((log ā₂ − log ā₁)/(m₂ − m₁)), so that the
//! damage per cycle min(Δσ^m₁/ā₁, Δσ^m₂/ā₂) is continuous; Δσ* lies within 0.1 % of the
//! standard's knee stress for every class (tested). Its derivative jumps there (by the factor
//! m₂/m₁): [`SnCurve::cycle_damage_derivative`] takes the derivative of the segment that
//! governs, the m₁ segment at Δσ ≥ Δσ* (the one-sided derivative from above at the knee itself).

use std::fmt;
use std::str::FromStr;

use crate::base::Scalar;

use super::FatigueError;

/// DNV-RP-C203 detail class (the S-N curve's name): B1, B2, C, C1, C2, D, E, F, F1, F3, G, W1,
/// W2, W3 (Tables 2-1 to 2-3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DnvClass {
    /// B1.
    B1,
    /// B2.
    B2,
    /// C.
    C,
    /// C1.
    C1,
    /// C2.
    C2,
    /// D.
    D,
    /// E.
    E,
    /// F.
    F,
    /// F1.
    F1,
    /// F3.
    F3,
    /// G.
    G,
    /// W1.
    W1,
    /// W2.
    W2,
    /// W3.
    W3,
}

/// The environment of the detail, which selects the table: DNV-RP-C203 Table 2-1 (air),
/// Table 2-2 (seawater with cathodic protection) or Table 2-3 (seawater, free corrosion).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Environment {
    /// In air (Table 2-1), scene value `"air"`: two slopes, knee at N = 10⁷.
    Air,
    /// In seawater with cathodic protection (Table 2-2), scene value `"seawater-cp"`: two slopes,
    /// knee at N = 10⁶.
    SeawaterCp,
    /// In seawater under free corrosion (Table 2-3), scene value `"free-corrosion"`: one slope,
    /// m = 3.
    FreeCorrosion,
}

/// One row of DNV-RP-C203 (April 2016) Tables 2-1, 2-2 and 2-3.
struct Row {
    class: DnvClass,
    /// m₁, Tables 2-1 and 2-2 (N ≤ 10⁷ in air, N ≤ 10⁶ in seawater with CP).
    m1: f64,
    /// log ā₁ in air, Table 2-1.
    log_a1_air: f64,
    /// log ā₁ in seawater with cathodic protection, Table 2-2.
    log_a1_cp: f64,
    /// log ā₂ (m₂ = 5), the same in Tables 2-1 and 2-2.
    log_a2: f64,
    /// log ā under free corrosion (m = 3), Table 2-3.
    log_a_fc: f64,
    /// Thickness exponent k, Tables 2-1 to 2-3.
    k: f64,
}

/// m₂ of Tables 2-1 and 2-2 (every class).
const M2: f64 = 5.0;
/// m of Table 2-3 (free corrosion, every class).
const M_FREE_CORROSION: f64 = 3.0;
/// The reference thickness t_ref = 25 mm of §2.4.3 for welded connections other than tubular
/// joints (tubular joints: 32 mm; give it explicitly).
pub const DNV_REFERENCE_THICKNESS_M: f64 = 0.025;

/// DNVGL-RP-C203 (April 2016): Table 2-1 (S-N curves in air: m₁, log ā₁ for N ≤ 10⁷, log ā₂
/// for N > 10⁷ with m₂ = 5, thickness exponent k), Table 2-2 (seawater with cathodic
/// protection: log ā₁ for N ≤ 10⁶, log ā₂ for N > 10⁶, same m₁, m₂ and k) and Table 2-3
/// (seawater, free corrosion: log ā with m = 3, same k). The thickness exponents of C, C1 and
/// C2 (0.05, 0.10, 0.15) are the 2016 edition's; the 2011 edition had 0.15 for all three.
#[rustfmt::skip]
const TABLE: [Row; 14] = [
    //                     m1    log ā1 air  log ā1 CP  log ā2   log ā FC   k
    Row { class: DnvClass::B1, m1: 4.0, log_a1_air: 15.117, log_a1_cp: 14.917, log_a2: 17.146, log_a_fc: 12.436, k: 0.00 },
    Row { class: DnvClass::B2, m1: 4.0, log_a1_air: 14.885, log_a1_cp: 14.685, log_a2: 16.856, log_a_fc: 12.262, k: 0.00 },
    Row { class: DnvClass::C,  m1: 3.0, log_a1_air: 12.592, log_a1_cp: 12.192, log_a2: 16.320, log_a_fc: 12.115, k: 0.05 },
    Row { class: DnvClass::C1, m1: 3.0, log_a1_air: 12.449, log_a1_cp: 12.049, log_a2: 16.081, log_a_fc: 11.972, k: 0.10 },
    Row { class: DnvClass::C2, m1: 3.0, log_a1_air: 12.301, log_a1_cp: 11.901, log_a2: 15.835, log_a_fc: 11.824, k: 0.15 },
    Row { class: DnvClass::D,  m1: 3.0, log_a1_air: 12.164, log_a1_cp: 11.764, log_a2: 15.606, log_a_fc: 11.687, k: 0.20 },
    Row { class: DnvClass::E,  m1: 3.0, log_a1_air: 12.010, log_a1_cp: 11.610, log_a2: 15.350, log_a_fc: 11.533, k: 0.20 },
    Row { class: DnvClass::F,  m1: 3.0, log_a1_air: 11.855, log_a1_cp: 11.455, log_a2: 15.091, log_a_fc: 11.378, k: 0.25 },
    Row { class: DnvClass::F1, m1: 3.0, log_a1_air: 11.699, log_a1_cp: 11.299, log_a2: 14.832, log_a_fc: 11.222, k: 0.25 },
    Row { class: DnvClass::F3, m1: 3.0, log_a1_air: 11.546, log_a1_cp: 11.146, log_a2: 14.576, log_a_fc: 11.068, k: 0.25 },
    Row { class: DnvClass::G,  m1: 3.0, log_a1_air: 11.398, log_a1_cp: 10.998, log_a2: 14.330, log_a_fc: 10.921, k: 0.25 },
    Row { class: DnvClass::W1, m1: 3.0, log_a1_air: 11.261, log_a1_cp: 10.861, log_a2: 14.101, log_a_fc: 10.784, k: 0.25 },
    Row { class: DnvClass::W2, m1: 3.0, log_a1_air: 11.107, log_a1_cp: 10.707, log_a2: 13.845, log_a_fc: 10.630, k: 0.25 },
    Row { class: DnvClass::W3, m1: 3.0, log_a1_air: 10.970, log_a1_cp: 10.570, log_a2: 13.617, log_a_fc: 10.493, k: 0.25 },
];

impl DnvClass {
    /// Every class, in the order of the tables.
    pub const ALL: [DnvClass; 14] = [
        DnvClass::B1,
        DnvClass::B2,
        DnvClass::C,
        DnvClass::C1,
        DnvClass::C2,
        DnvClass::D,
        DnvClass::E,
        DnvClass::F,
        DnvClass::F1,
        DnvClass::F3,
        DnvClass::G,
        DnvClass::W1,
        DnvClass::W2,
        DnvClass::W3,
    ];

    /// The class's name as the standard writes it (`"D"`, `"F1"`).
    pub fn name(self) -> &'static str {
        match self {
            DnvClass::B1 => "B1",
            DnvClass::B2 => "B2",
            DnvClass::C => "C",
            DnvClass::C1 => "C1",
            DnvClass::C2 => "C2",
            DnvClass::D => "D",
            DnvClass::E => "E",
            DnvClass::F => "F",
            DnvClass::F1 => "F1",
            DnvClass::F3 => "F3",
            DnvClass::G => "G",
            DnvClass::W1 => "W1",
            DnvClass::W2 => "W2",
            DnvClass::W3 => "W3",
        }
    }

    fn row(self) -> &'static Row {
        // The table lists the classes in the order of their declaration (tested).
        let row = &TABLE[self as usize];
        debug_assert_eq!(row.class, self);
        row
    }

    /// The thickness exponent k of DNV-RP-C203 (April 2016) Tables 2-1 to 2-3 for this class.
    pub fn thickness_exponent(self) -> f64 {
        self.row().k
    }
}

impl fmt::Display for DnvClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DnvClass {
    type Err = FatigueError;
    /// Parses the class's name (`"D"`, `"F1"`, case-sensitive as the standard writes it).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DnvClass::ALL
            .iter()
            .copied()
            .find(|c| c.name() == s)
            .ok_or_else(|| FatigueError::UnknownCurve {
                name: s.to_string(),
            })
    }
}

impl Environment {
    /// Every environment.
    pub const ALL: [Environment; 3] = [
        Environment::Air,
        Environment::SeawaterCp,
        Environment::FreeCorrosion,
    ];

    /// The scene file's name: `"air"`, `"seawater-cp"`, `"free-corrosion"`.
    pub fn name(self) -> &'static str {
        match self {
            Environment::Air => "air",
            Environment::SeawaterCp => "seawater-cp",
            Environment::FreeCorrosion => "free-corrosion",
        }
    }
}

impl fmt::Display for Environment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Environment {
    type Err = FatigueError;
    /// Parses `"air"`, `"seawater-cp"` or `"free-corrosion"`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Environment::ALL
            .iter()
            .copied()
            .find(|e| e.name() == s)
            .ok_or_else(|| FatigueError::UnknownEnvironment {
                name: s.to_string(),
            })
    }
}

/// One straight segment of an S-N curve: N = ā · Δσ^(−m) (DNV-RP-C203 eq. 2.4.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The negative inverse slope m.
    pub m: f64,
    /// log₁₀ ā, the intercept of the log N axis (Δσ in MPa).
    pub log_a: f64,
}

impl Segment {
    /// Damage of one cycle of range Δσ on this segment: 1/N = Δσ^m / ā.
    fn damage<D: Scalar>(&self, range: D) -> D {
        range.powf(self.m) * 10f64.powf(-self.log_a)
    }

    /// d(Δσ^m/ā)/dΔσ = m Δσ^(m−1) / ā.
    fn damage_derivative(&self, range: f64) -> f64 {
        self.m * range.powf(self.m - 1.0) * 10f64.powf(-self.log_a)
    }
}

/// An S-N curve with one or two slopes and a thickness correction, ranges in MPa.
///
/// Damage of one cycle of range Δσ (Miner, DNV-RP-C203 eq. 2.3.1 with eq. 2.4.1 and 2.4.3):
///
/// d(Δσ) = 1/N(s Δσ) = min((s Δσ)^m₁/ā₁, (s Δσ)^m₂/ā₂),  s = (t_eff/t_ref)^k,
///
/// the second term absent for a one-slope curve (see the module's docs for the knee).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnCurve {
    /// The high-range segment (m₁, log ā₁); the only one of a one-slope curve.
    pub first: Segment,
    /// The low-range segment (m₂, log ā₂), if the curve has two slopes.
    pub second: Option<Segment>,
    /// The thickness factor s = (t_eff/t_ref)^k ≥ 1 that multiplies every stress range.
    pub thickness_factor: f64,
}

impl SnCurve {
    /// The DNV-RP-C203 (April 2016) curve of `class` in `environment`, without thickness
    /// correction (s = 1): Table 2-1, 2-2 or 2-3.
    pub fn dnv(class: DnvClass, environment: Environment) -> SnCurve {
        let row = class.row();
        let (first, second) = match environment {
            Environment::Air => (
                Segment {
                    m: row.m1,
                    log_a: row.log_a1_air,
                },
                Some(Segment {
                    m: M2,
                    log_a: row.log_a2,
                }),
            ),
            Environment::SeawaterCp => (
                Segment {
                    m: row.m1,
                    log_a: row.log_a1_cp,
                },
                Some(Segment {
                    m: M2,
                    log_a: row.log_a2,
                }),
            ),
            Environment::FreeCorrosion => (
                Segment {
                    m: M_FREE_CORROSION,
                    log_a: row.log_a_fc,
                },
                None,
            ),
        };
        SnCurve {
            first,
            second,
            thickness_factor: 1.0,
        }
    }

    /// A one-slope curve N = ā Δσ^(−m) (for closed-form checks, e.g. the narrow-band formula).
    pub fn one_slope(m: f64, log_a: f64) -> SnCurve {
        SnCurve {
            first: Segment { m, log_a },
            second: None,
            thickness_factor: 1.0,
        }
    }

    /// The same curve with the thickness correction of DNV-RP-C203 eq. 2.4.3:
    /// s = (max(t, t_ref)/t_ref)^k (thicknesses in any one unit; no correction below t_ref).
    ///
    /// # Errors
    /// [`FatigueError::InvalidSpec`] if t or t_ref is not positive and finite, or k is negative
    /// or not finite.
    pub fn with_thickness(
        self,
        thickness: f64,
        reference: f64,
        exponent: f64,
    ) -> Result<SnCurve, FatigueError> {
        super::check_positive("wall_thickness", thickness)?;
        super::check_positive("reference_thickness", reference)?;
        if !(exponent.is_finite() && exponent >= 0.0) {
            return Err(FatigueError::InvalidSpec {
                key: "thickness_exponent",
                value: exponent,
                reason: "must be finite and ≥ 0",
            });
        }
        let thickness_factor = (thickness.max(reference) / reference).powf(exponent);
        Ok(SnCurve {
            thickness_factor,
            ..self
        })
    }

    /// The stress range Δσ* (MPa, before the thickness factor) where the two segments meet,
    /// 10^((log ā₂ − log ā₁)/(m₂ − m₁)) / s; `None` for a one-slope curve.
    pub fn knee_range(&self) -> Option<f64> {
        self.second.map(|b| {
            let a = self.first;
            10f64.powf((b.log_a - a.log_a) / (b.m - a.m)) / self.thickness_factor
        })
    }

    /// The segment that governs a cycle of range Δσ (MPa): the first at s Δσ ≥ Δσ*.
    pub fn segment(&self, range: f64) -> Segment {
        match (self.second, self.knee_range()) {
            (Some(low), Some(knee)) if range < knee => low,
            _ => self.first,
        }
    }

    /// The slope m of the segment that governs the range Δσ (the exponent of the smooth proxy
    /// Σ|σ|^m is the first slope's, [`SnCurve::first`]).
    pub fn slope(&self, range: f64) -> f64 {
        self.segment(range).m
    }

    /// Cycles to failure N(Δσ) = ā (s Δσ)^(−m) on the governing segment (∞ at Δσ = 0).
    pub fn cycles_to_failure(&self, range: f64) -> f64 {
        1.0 / self.cycle_damage(range)
    }

    /// Damage of one full cycle of range Δσ (MPa): d(Δσ) = (s Δσ)^m/ā on the governing
    /// segment (the type's docs). Generic over the scalar so a fixed pairing can be
    /// differentiated with dual numbers; the segment is chosen on the real part.
    pub fn cycle_damage<D: Scalar>(&self, range: D) -> D {
        if range.re() <= 0.0 {
            return range * 0.0;
        }
        self.segment(range.re())
            .damage(range * self.thickness_factor)
    }

    /// d d(Δσ)/dΔσ = s · m (s Δσ)^(m−1)/ā on the governing segment (at the knee itself: the
    /// m₁ segment's, the one-sided derivative from above).
    pub fn cycle_damage_derivative(&self, range: f64) -> f64 {
        if range <= 0.0 {
            return 0.0;
        }
        let s = self.thickness_factor;
        s * self.segment(range).damage_derivative(s * range)
    }
}
