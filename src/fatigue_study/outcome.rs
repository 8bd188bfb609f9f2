//! What a fatigue study returns: per controller the life over the scatter diagram and its spread
//! over seeds, per cell and hot spot the damage, the thrust used, and the cells where a
//! controller did worse than none ([`Study`]).

use super::*;

/// A controller's moment record on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlledRecord {
    /// M₀(t_k) \[N·m\], k = 0..N.
    pub moment: Vec<f64>,
    /// M₀ₓ of a spatial run.
    pub moment_x: Option<Vec<f64>>,
    /// T = N h \[s\].
    pub duration_s: f64,
    /// The constant controller's force \[N\].
    pub force: Option<f64>,
    /// The PD law's gains (u_b \[N\], K_p \[N/(N·m)\], K_d \[N·s/(N·m)\]).
    pub gains: Option<[f64; 3]>,
    /// A closed loop's decisions: the force \[N\] held over each control interval, in order
    /// (`None` for `scene` and `none`), from which [`replay_joint_moments`] recomputes the
    /// run's joint torques.
    pub decisions: Option<Vec<f64>>,
    /// The thrust applied, when the control is the thrust on the vessel: (rms, peak) \[N\] of
    /// F_k over k = 0..N ([`thrust_stats`]; `none`: zero); `None` otherwise.
    pub thrust: Option<[f64; 2]>,
}

/// (rms, peak) of the thrusts F_0..F_N: (Σ F_k²/(N + 1))^½ and max |F_k| \[N\].
pub fn thrust_stats(thrust: &[f64]) -> [f64; 2] {
    if thrust.is_empty() {
        return [0.0; 2];
    }
    let ms = thrust.iter().map(|f| f * f).sum::<f64>() / thrust.len() as f64;
    [ms.sqrt(), thrust.iter().fold(0.0f64, |m, f| m.max(f.abs()))]
}

/// One controller's outcome in one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellOutcome {
    /// The cell's sea state (`None`: the scene as is, without `[loads.waves]`).
    pub sea: Option<SeaState>,
    /// p_s.
    pub probability: f64,
    /// Miner's sum D_{c,s} over the record: the mean over the seeds of `seed_damages`.
    pub damage: f64,
    /// Miner's sum of each seed's record, in seed order (one value with one seed).
    pub seed_damages: Vec<f64>,
    /// T_s \[s\].
    pub duration_s: f64,
    /// The cell's probability-weighted contribution p_s · D_{c,s} · Y/T_s per year.
    pub damage_per_year: f64,
    /// The constant controller's force in this cell \[N\].
    pub force: Option<f64>,
    /// The PD law's gains in this cell.
    pub gains: Option<[f64; 3]>,
    /// The thrust on the vessel in this cell (a thrust scene): (rms over its seeds' records,
    /// the largest |F| of any seed) \[N\].
    pub thrust: Option<[f64; 2]>,
}

/// The spread of a cell's Miner sum over its seeds ([`CellOutcome::seed_spread`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeedSpread {
    /// The sample standard deviation s = √(Σᵢ (Dᵢ − D̄)² / (K − 1)).
    pub std: f64,
    /// minᵢ Dᵢ.
    pub min: f64,
    /// maxᵢ Dᵢ.
    pub max: f64,
}

impl CellOutcome {
    /// With more than one seed, the spread of the seeds' Miner sums Dᵢ about their mean D̄
    /// (`damage`); `None` with one seed.
    pub fn seed_spread(&self) -> Option<SeedSpread> {
        let k = self.seed_damages.len();
        (k > 1).then(|| {
            let ss: f64 = self
                .seed_damages
                .iter()
                .map(|d| (d - self.damage).powi(2))
                .sum();
            let d = self.seed_damages.iter().copied();
            SeedSpread {
                std: (ss / (k - 1) as f64).sqrt(),
                min: d.clone().fold(f64::INFINITY, f64::min),
                max: d.fold(f64::NEG_INFINITY, f64::max),
            }
        })
    }
}

/// The range of the lives of a controller's seeds ([`ControllerOutcome::seed_life_range`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LifeRange {
    /// minᵢ Lᵢ \[years\] (+∞: no seed does damage).
    pub min: f64,
    /// maxᵢ Lᵢ \[years\].
    pub max: f64,
}

impl ControllerOutcome {
    /// With more than one seed, the least and greatest of the seeds' lives `seed_lives`; `None`
    /// with one seed.
    pub fn seed_life_range(&self) -> Option<LifeRange> {
        let l = self.seed_lives.iter().copied();
        (self.seed_lives.len() > 1).then(|| LifeRange {
            min: l.clone().fold(f64::INFINITY, f64::min),
            max: l.fold(f64::NEG_INFINITY, f64::max),
        })
    }
}

/// One controller over every cell.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerOutcome {
    /// The controller.
    pub kind: ControllerKind,
    /// D_y = Σ_s of the cells' contributions.
    pub damage_per_year: f64,
    /// L = 1/(DFF · D_y) years (+∞ without damage).
    pub life_years: f64,
    /// Per cell, in the diagram's order.
    pub cells: Vec<CellOutcome>,
    /// The life of each seed alone, L_i = 1/(DFF · Σ_s p_s D_{c,s,i} Y/T_s) years, in seed
    /// order (one value, `life_years`, with one seed).
    pub seed_lives: Vec<f64>,
    /// Per hot spot of the scene's `[[fatigue.hotspot]]` (empty without them): the damage per
    /// year and life over the diagram, each cell's the mean over the seeds.
    pub hotspots: Vec<HotSpotOutcome>,
    /// The thrust on the vessel over the diagram (a thrust scene): the rms
    /// (Σ_s p_s F²_rms,s / Σ_s p_s)^½ \[N\], the cells' mean squares weighted by their
    /// probabilities.
    pub thrust_rms: Option<f64>,
    /// The largest |F| of any cell and seed \[N\].
    pub thrust_peak: Option<f64>,
}

/// A hot spot's outcome over the diagram, for one controller.
#[derive(Clone, Debug, PartialEq)]
pub struct HotSpotOutcome {
    /// The hot spot's name.
    pub name: String,
    /// Its elevation \[m\].
    pub elevation: f64,
    /// D_y = Σ_s p_s · D̄_s · Y/T_s, D̄_s the mean over the seeds of cell s.
    pub damage_per_year: f64,
    /// 1/(DFF · D_y) years (+∞ without damage).
    pub life_years: f64,
    /// The hot spot's design fatigue factor DFF.
    pub dff: f64,
}

/// A cell where a closed-loop controller's damage is above no control's
/// ([`Study::worse_than_none`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorseThanNone {
    /// The controller.
    pub controller: ControllerKind,
    /// The cell (0-based, in the diagram's order).
    pub cell: usize,
    /// Its damage D_{c,s} (mean over the seeds).
    pub damage: f64,
    /// No control's damage in the same cell.
    pub none: f64,
}

/// The outcome of [`run_study`]: one entry per controller, in report order.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// Per controller.
    pub controllers: Vec<ControllerOutcome>,
}

impl Study {
    /// The outcome of `kind`, if it was run.
    pub fn get(&self, kind: ControllerKind) -> Option<&ControllerOutcome> {
        self.controllers.iter().find(|c| c.kind == kind)
    }

    /// D_{c,s}/D_{none,s}, the damage of `kind` in cell s over no control's; `None` unless both
    /// ran, or when no control does no damage there.
    pub fn damage_ratio_to_none(&self, kind: ControllerKind, cell: usize) -> Option<f64> {
        let (c, none) = (self.get(kind)?, self.get(ControllerKind::None)?);
        let (d, d0) = (c.cells.get(cell)?.damage, none.cells.get(cell)?.damage);
        (d0 > 0.0).then_some(d / d0)
    }

    /// Every (closed-loop controller, cell) whose damage is above no control's in that cell:
    /// a controller that does worse than none there (in cell then report order).
    pub fn worse_than_none(&self) -> Vec<WorseThanNone> {
        let Some(none) = self.get(ControllerKind::None) else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (s, cell0) in none.cells.iter().enumerate() {
            for c in self.controllers.iter().filter(|c| c.kind.is_feedback()) {
                if let Some(cell) = c.cells.get(s).filter(|x| x.damage > cell0.damage) {
                    out.push(WorseThanNone {
                        controller: c.kind,
                        cell: s,
                        damage: cell.damage,
                        none: cell0.damage,
                    });
                }
            }
        }
        out
    }

    /// L(kind)/L(none) = D_y(none)/D_y(kind); `None` unless both ran and both lives are
    /// finite and positive.
    pub fn life_extension(&self, kind: ControllerKind) -> Option<f64> {
        let (c, none) = (self.get(kind)?, self.get(ControllerKind::None)?);
        let ratio = c.life_years / none.life_years;
        (c.life_years.is_finite() && none.life_years.is_finite() && ratio.is_finite())
            .then_some(ratio)
    }
}
