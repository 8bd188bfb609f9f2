//! Miner's rule, annual damage, fatigue life and the combination of a scatter diagram
//! (DNV-RP-C203 §2.3, docs/fatigue.md).
//!
//! - Miner's sum over counted cycles: D = Σ nᵢ/N(Δσᵢ) (DNV-RP-C203 eq. 2.3.1), nᵢ = 1 for a full
//!   cycle and ½ for a half cycle.
//! - A record of duration T with damage D: damage per year D_y = D · Y/T, Y = 365.25 · 86 400 s
//!   ([`SECONDS_PER_YEAR`]).
//! - Life: L = 1/(DFF · D_y) years (DFF the design fatigue factor).
//! - Scatter diagram: sea state s with probability of occurrence p_s, a record of duration T_s
//!   and damage D_s contributes p_s · D_s · Y/T_s per year; the contributions add.

use super::rainflow::Cycle;
use super::sn::SnCurve;
use super::{check_positive, FatigueError};

/// Seconds in a (Julian) year, 365.25 · 86 400 s.
pub const SECONDS_PER_YEAR: f64 = 365.25 * 86_400.0;

/// Miner's sum D = Σ nᵢ · d(Δσᵢ) over the cycles (ranges in MPa; d from [`SnCurve::cycle_damage`]).
pub fn miner_sum(cycles: &[Cycle], curve: &SnCurve) -> f64 {
    cycles
        .iter()
        .map(|c| c.count * curve.cycle_damage(c.range))
        .sum()
}

/// The damage per year of a record: D_y = D · Y/T.
///
/// # Errors
/// [`FatigueError::InvalidSpec`] (`duration`) unless T is positive and finite;
/// [`FatigueError::NonFinite`] (`damage`) unless D is finite and ≥ 0.
pub fn damage_per_year(damage: f64, duration_s: f64) -> Result<f64, FatigueError> {
    check_positive("duration", duration_s)?;
    check_damage(damage, 0)?;
    Ok(damage * SECONDS_PER_YEAR / duration_s)
}

/// The fatigue life L = 1/(DFF · D_y) in years (+∞ when nothing is damaged).
///
/// # Errors
/// [`FatigueError::InvalidSpec`] (`dff`) unless DFF is positive and finite;
/// [`FatigueError::NonFinite`] (`damage`) unless D_y is finite and ≥ 0.
pub fn life_years(damage_per_year: f64, dff: f64) -> Result<f64, FatigueError> {
    check_positive("dff", dff)?;
    check_damage(damage_per_year, 0)?;
    Ok(1.0 / (dff * damage_per_year))
}

fn check_damage(damage: f64, index: usize) -> Result<(), FatigueError> {
    if !(damage.is_finite() && damage >= 0.0) {
        return Err(FatigueError::NonFinite {
            quantity: "damage",
            index,
            value: damage,
        });
    }
    Ok(())
}

/// One cell of a scatter diagram: the probability of its sea state and the damage of a record
/// of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellDamage {
    /// Probability of occurrence p_s ∈ \[0, 1\].
    pub probability: f64,
    /// Miner's sum D_s over the record.
    pub damage: f64,
    /// The record's duration T_s \[s\].
    pub duration_s: f64,
}

/// Damage per year over a scatter diagram.
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterDamage {
    /// Σ_s p_s · D_s · Y/T_s.
    pub damage_per_year: f64,
    /// Each cell's probability-weighted contribution p_s · D_s · Y/T_s, in the cells' order.
    pub cells: Vec<f64>,
    /// Σ_s p_s (1 for a complete diagram; less if cells were left out).
    pub probability_sum: f64,
}

/// Tolerance on Σ p_s ≤ 1 (probabilities printed to a few digits).
const PROBABILITY_SUM_TOLERANCE: f64 = 1e-6;

/// Combines the cells of a scatter diagram: D_y = Σ_s p_s · D_s · Y/T_s (the module's docs).
/// A pure function: the cells' damages come from any simulation.
///
/// # Errors
/// [`FatigueError::InvalidProbability`] naming the cell if a probability is outside \[0, 1\] or
/// not finite, [`FatigueError::ProbabilitySum`] if they add up to more than 1 (+10⁻⁶),
/// [`FatigueError::EmptyDiagram`] if there is no cell or they add up to 0 (no time at all: not
/// an infinite life),
/// [`FatigueError::InvalidSpec`] (`duration`) or [`FatigueError::NonFinite`] (`damage`, with
/// the cell's index) for a bad record.
pub fn combine_scatter(cells: &[CellDamage]) -> Result<ScatterDamage, FatigueError> {
    let mut out = Vec::with_capacity(cells.len());
    let mut probability_sum = 0.0;
    for (index, cell) in cells.iter().enumerate() {
        let p = cell.probability;
        if !(p.is_finite() && (0.0..=1.0).contains(&p)) {
            return Err(FatigueError::InvalidProbability { index, value: p });
        }
        check_damage(cell.damage, index)?;
        probability_sum += p;
        out.push(p * damage_per_year(cell.damage, cell.duration_s)?);
    }
    if probability_sum > 1.0 + PROBABILITY_SUM_TOLERANCE {
        return Err(FatigueError::ProbabilitySum {
            sum: probability_sum,
        });
    }
    // A diagram of probability 0 describes no time at all: its damage 0 would be an infinite
    // life read from nothing.
    if cells.is_empty() || probability_sum <= 0.0 {
        return Err(FatigueError::EmptyDiagram { cells: cells.len() });
    }
    Ok(ScatterDamage {
        damage_per_year: out.iter().sum(),
        cells: out,
        probability_sum,
    })
}
