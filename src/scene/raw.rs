//! The file-shaped (TOML) structures and their conversion to and from [`Scene`]; serde's errors
//! become keyed [`SceneError`]s in [`super::toml_errors`].

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::de::DeTable;

use super::current::RawCurrent;
use super::fatigue::RawFatigue;
use super::limits::check_size;
use super::objective::RawObjective;
use super::toml_errors::{classify, syntax_error};
use super::validate::{node_index, positive_count};
use super::values::{to_i64, NumOrArray, RawValues};
use super::{
    Control, ControlKind, Harmonic, Initial, LoadSeries, Loads, PointLoad, Scene, SceneError,
    SceneErrorKind, Support, TimeGrid,
};

/// Parses TOML text into the raw structures; errors name the key.
pub(super) fn parse(text: &str) -> Result<RawScene, SceneError> {
    let doc = DeTable::parse(text).map_err(|e| syntax_error(text, &e))?;
    toml::from_str(text).map_err(|e| classify(text, &e, &doc))
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_positive_zero(x: &f64) -> bool {
    x.to_bits() == 0
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    beam: RawBeam,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pipe: Option<super::Pipe>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    water: Option<super::Water>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    soil: Option<super::Soil>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    loads: Option<RawLoads>,
    // After `loads`: TOML writes the stack-up's arrays of tables after the plain tables.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stackup: Option<super::Stackup>,
    time: RawTime,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    control: Option<RawControl>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    objective: Option<RawObjective>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fatigue: Option<RawFatigue>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mpc: Option<super::mpc::RawMpc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vessel: Option<super::Vessel>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    design: Option<super::design::RawDesign>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBeam {
    pendulums: i64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    length: Option<NumOrArray>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mass: Option<NumOrArray>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stiffness: Option<NumOrArray>,
    support: Support,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    base_stiffness: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tip_stiffness: Option<f64>,
    #[serde(default, skip_serializing_if = "is_false")]
    reaction_force: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    joint_damping: Option<NumOrArray>,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawLoads {
    #[serde(default)]
    gravity: f64,
    #[serde(default)]
    drag: f64,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    tension: f64,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    axial_weight: f64,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    point: Vec<RawPoint>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    current: Option<RawCurrent>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    waves: Option<super::waves::RawWaves>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPoint {
    node: i64,
    /// F (along z) or [F_x, F_z]; optional when the load has harmonics or a series.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    force: Option<NumOrArray>,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    start: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end: Option<f64>,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    ramp: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    direction: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    series: Option<String>,
    // Tables last: TOML writes plain values before sub-tables.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    harmonic: Vec<RawHarmonic>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHarmonic {
    amplitude: f64,
    period: f64,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    phase: f64,
}

impl RawPoint {
    fn from_load(p: &PointLoad) -> Self {
        let varying = !p.harmonics.is_empty() || p.series.is_some();
        let force = if p.force_x.to_bits() != 0 {
            Some(NumOrArray::Array(vec![p.force_x, p.force]))
        } else if p.force.to_bits() != 0 || !varying {
            Some(NumOrArray::Number(p.force))
        } else {
            None
        };
        let default_direction =
            p.direction[0].to_bits() == 0 && p.direction[1].to_bits() == 1f64.to_bits();
        RawPoint {
            node: to_i64(p.node),
            force,
            start: p.start,
            end: p.end,
            ramp: p.ramp,
            direction: (!p.harmonics.is_empty() && !default_direction)
                .then(|| p.direction.to_vec()),
            series: p
                .series
                .as_ref()
                .map(|s| s.file.to_string_lossy().into_owned()),
            harmonic: p
                .harmonics
                .iter()
                .map(|h| RawHarmonic {
                    amplitude: h.amplitude,
                    period: h.period,
                    phase: h.phase,
                })
                .collect(),
        }
    }

    /// The load of `loads.point[i]`; a `series` file is read relative to `dir` (if given).
    fn into_load(self, i: usize, n: usize, dir: Option<&Path>) -> Result<PointLoad, SceneError> {
        let key = |k: &str| format!("loads.point[{i}].{k}");
        let node = node_index(&key("node"), self.node, n)?;
        let varying = !self.harmonic.is_empty() || self.series.is_some();
        let [force_x, force] = match self.force {
            Some(NumOrArray::Number(f)) => [0.0, f],
            Some(NumOrArray::Array(v)) => match v[..] {
                [fx, fz] => [fx, fz],
                _ => {
                    return Err(SceneError::invalid(
                        key("force"),
                        format!(
                            "a vector force has 2 components [fx, fz] (transverse to the beam, \
                             which lies along y), got {} values",
                            v.len()
                        ),
                    ))
                }
            },
            None if varying => [0.0, 0.0],
            None => {
                return Err(SceneErrorKind::MissingKey {
                    key: key("force"),
                    note: Some("required unless the load has a `harmonic` or a `series`".into()),
                }
                .into())
            }
        };
        let direction = match self.direction {
            None => [0.0, 1.0],
            Some(_) if self.harmonic.is_empty() => {
                return Err(SceneError::invalid(
                    key("direction"),
                    "the direction applies to the load's harmonics, and it has none: add \
                     [[loads.point.harmonic]] tables, or give a constant force as `force = [fx, fz]`",
                ))
            }
            Some(v) => match v[..] {
                [dx, dz] => [dx, dz],
                _ => {
                    return Err(SceneError::invalid(
                        key("direction"),
                        format!(
                            "a direction has 2 components [dx, dz] (transverse to the beam), got \
                             {} values",
                            v.len()
                        ),
                    ))
                }
            },
        };
        let series = match self.series {
            None => None,
            Some(name) => {
                let written = PathBuf::from(&name);
                let resolved = match dir {
                    Some(d) if written.is_relative() => d.join(&written),
                    _ => written.clone(),
                };
                Some(LoadSeries::read_at(&key("series"), &written, &resolved)?)
            }
        };
        Ok(PointLoad {
            node,
            force,
            force_x,
            start: self.start,
            end: self.end,
            ramp: self.ramp,
            direction,
            harmonics: self
                .harmonic
                .into_iter()
                .map(|h| Harmonic {
                    amplitude: h.amplitude,
                    period: h.period,
                    phase: h.phase,
                })
                .collect(),
            series,
        })
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    step: f64,
    steps: i64,
    #[serde(default, skip_serializing_if = "Initial::is_rest")]
    initial: Initial,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawControl {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    node: Option<i64>,
    kind: ControlKind,
    /// u (along z) each, or [u_x, u_z] each (a 2-axis control); or one number for every value;
    /// or absent (zeros).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    values: Option<RawValues>,
}

impl RawControl {
    /// The `[control]` table of a chain of `n` pendulums over `steps` steps. One number: every
    /// value equal (N + 1 for per-step, 1 piece for piecewise); absent: zeros. The node defaults
    /// to the tip n.
    fn into_control(self, n: usize, steps: usize) -> Result<Control, SceneError> {
        let count = match self.kind {
            ControlKind::PerStep => steps + 1,
            ControlKind::Constant | ControlKind::Piecewise => 1,
        };
        let (values, values_x) = match self.values {
            Some(RawValues::Many(v)) => RawControl::split_values(v)?,
            Some(RawValues::One(u)) => (vec![u; count], None),
            None => (vec![0.0; count], None),
        };
        Ok(Control {
            node: match self.node {
                Some(node) => node_index("control.node", node, n)?,
                None => n,
            },
            kind: self.kind,
            values,
            values_x,
        })
    }

    /// The values as (z components, x components of a 2-axis control): every value a number
    /// (1-axis) or every value a pair [u_x, u_z] (2-axis).
    fn split_values(values: Vec<NumOrArray>) -> Result<(Vec<f64>, Option<Vec<f64>>), SceneError> {
        let two_axis = matches!(values.first(), Some(NumOrArray::Array(_)));
        let (mut vz, mut vx) = (Vec::with_capacity(values.len()), Vec::new());
        for (i, v) in values.into_iter().enumerate() {
            let key = format!("control.values[{i}]");
            match (v, two_axis) {
                (NumOrArray::Number(u), false) => vz.push(u),
                (NumOrArray::Array(p), true) if p.len() == 2 => {
                    vx.push(p[0]);
                    vz.push(p[1]);
                }
                (NumOrArray::Array(p), true) => {
                    return Err(SceneError::invalid(
                        key,
                        format!(
                            "a 2-axis control value is a pair [u_x, u_z], got {} numbers",
                            p.len()
                        ),
                    ))
                }
                _ => {
                    return Err(SceneError::invalid(
                        key,
                        "the values of one control are all numbers u (along z) or all pairs \
                         [u_x, u_z] (2-axis)",
                    ))
                }
            }
        }
        Ok((vz, two_axis.then_some(vx)))
    }

    /// The scene's values as written: numbers, or pairs [u_x, u_z] for a 2-axis control.
    fn join_values(c: &Control) -> Vec<NumOrArray> {
        match &c.values_x {
            None => c.values.iter().map(|&u| NumOrArray::Number(u)).collect(),
            Some(vx) => vx
                .iter()
                .zip(&c.values)
                .map(|(&x, &z)| NumOrArray::Array(vec![x, z]))
                .collect(),
        }
    }
}

impl RawScene {
    pub(super) fn from_scene(s: &Scene) -> Self {
        let b = &s.beam;
        let given = s.pipe.is_none() && s.stackup.is_none();
        let stack = s.stackup.is_some();
        RawScene {
            beam: RawBeam {
                pendulums: to_i64(s.n()),
                length: given.then(|| NumOrArray::compact(&b.lengths)),
                mass: given.then(|| NumOrArray::compact(&b.masses)),
                stiffness: given.then(|| NumOrArray::compact(&b.stiffness)),
                support: b.support,
                base_stiffness: (!stack).then_some(b.base_stiffness),
                tip_stiffness: (!stack).then_some(b.tip_stiffness),
                reaction_force: b.reaction_force,
                joint_damping: (!b.joint_damping.is_empty())
                    .then(|| NumOrArray::compact(&b.joint_damping)),
            },
            pipe: s.pipe,
            water: (!s.water.is_default()).then_some(s.water),
            soil: s.soil,
            stackup: s.stackup.clone(),
            loads: Some(RawLoads {
                gravity: s.loads.gravity,
                // The stack-up's drag comes from its coefficients (read back, it is recomputed).
                drag: if stack { 0.0 } else { s.loads.drag },
                tension: s.loads.tension,
                axial_weight: s.loads.axial_weight,
                point: s.loads.points.iter().map(RawPoint::from_load).collect(),
                current: s.loads.current.as_ref().map(RawCurrent::from_current),
                waves: s
                    .loads
                    .waves
                    .as_ref()
                    .map(super::waves::RawWaves::from_waves),
            }),
            time: RawTime {
                step: s.time.step,
                steps: to_i64(s.time.steps),
                initial: s.time.initial,
            },
            control: s.control.as_ref().map(|c| RawControl {
                node: Some(to_i64(c.node)),
                kind: c.kind,
                values: Some(RawValues::Many(RawControl::join_values(c))),
            }),
            objective: s.objective.map(RawObjective::from_kind),
            fatigue: s
                .fatigue
                .as_ref()
                .map(|f| RawFatigue::from_spec(f).with_hotspots(&s.hotspots)),
            mpc: s.mpc.as_ref().map(super::mpc::RawMpc::from_table),
            vessel: s.vessel.clone(),
            design: s.design.as_ref().map(super::design::RawDesign::from_table),
        }
    }

    /// The scene; `series` files are read relative to `dir` (the current directory if `None`).
    pub(super) fn into_scene(self, dir: Option<&Path>) -> Result<Scene, SceneError> {
        let n = positive_count("beam.pendulums", self.beam.pendulums)?;
        let steps = positive_count("time.steps", self.time.steps)?;
        check_size(n, steps)?;
        let b = self.beam;
        let water = self.water.unwrap_or_default();
        let joint_damping = match b.joint_damping {
            None => Vec::new(),
            Some(c) => super::validate::joint_damping_layout(c, n, b.support)?,
        };
        let keys = super::pipe::BeamKeys {
            n,
            length: b.length,
            mass: b.mass,
            stiffness: b.stiffness,
            end_springs: (b.base_stiffness, b.tip_stiffness),
            support: b.support,
            reaction_force: b.reaction_force,
        };
        let mut stackup = self.stackup;
        let mut raw_loads = self.loads.unwrap_or_default();
        let mut beam = match stackup.as_mut() {
            Some(st) => {
                let mudline = self.soil.map_or(0.0, |s| s.mudline);
                let loads = (raw_loads.drag, raw_loads.axial_weight);
                let beam =
                    keys.into_stackup_beam(st, self.pipe.is_some(), loads, &water, mudline)?;
                // Morison's drag node by node takes no momentum-drag constant.
                if st.drag_model == super::DragModel::Momentum {
                    raw_loads.drag = st.drag_constants(&beam.lengths, &beam.masses, mudline).0;
                }
                beam
            }
            None => keys.into_beam(self.pipe.as_ref(), &water)?,
        };
        beam.joint_damping = joint_damping;
        let mut points = Vec::with_capacity(raw_loads.point.len());
        for (i, p) in raw_loads.point.into_iter().enumerate() {
            points.push(p.into_load(i, n, dir)?);
        }
        let control = self.control.map(|c| c.into_control(n, steps)).transpose()?;
        let mut current = raw_loads
            .current
            .map(RawCurrent::into_current)
            .transpose()?;
        super::pipe::reconcile_surface(&water, current.as_mut())?;
        let (fatigue, raw_hotspots) = match self.fatigue.map(RawFatigue::split_hotspots) {
            Some((table, hotspots)) => (Some(table.into_spec(self.pipe.as_ref())?), hotspots),
            None => (None, Vec::new()),
        };
        let hotspots = super::fatigue::hotspots_of(raw_hotspots, fatigue.as_ref())?;
        let base_length = beam.lengths.first().copied().unwrap_or(f64::NAN);
        // Without a [fatigue] table a [pipe]'s section serves (`Scene::fatigue_spec`).
        let assessed = fatigue.or_else(|| {
            self.pipe
                .map(|p| crate::fatigue::FatigueSpec::new(p.outer_diameter, p.wall_thickness))
        });
        let objective = self
            .objective
            .map(|o| o.into_kind(assessed.as_ref(), base_length))
            .transpose()?;
        // `support = "vessel"` without `[vessel]`: a vessel that holds the top still.
        let vessel = match (self.vessel, beam.support) {
            (None, Support::Vessel) => Some(super::Vessel::default()),
            (v, _) => v,
        };
        Ok(Scene {
            beam,
            pipe: self.pipe,
            stackup,
            water,
            soil: self.soil,
            loads: Loads {
                gravity: raw_loads.gravity,
                drag: raw_loads.drag,
                tension: raw_loads.tension,
                axial_weight: raw_loads.axial_weight,
                points,
                current,
                waves: raw_loads
                    .waves
                    .map(super::waves::RawWaves::into_waves)
                    .transpose()?,
            },
            time: TimeGrid {
                step: self.time.step,
                steps,
                initial: self.time.initial,
            },
            control,
            objective,
            fatigue,
            hotspots,
            mpc: self.mpc.map(super::mpc::RawMpc::into_table).transpose()?,
            vessel,
            design: self
                .design
                .map(super::design::RawDesign::into_table)
                .transpose()?,
        })
    }
}
