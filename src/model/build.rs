//! Building a [`Chain`] from a scene ([`Chain::from_scene`]: every term's value from the scene's
//! keys, docs/scene-format.md) and lifting it to another scalar ([`Chain::lift`]).

use super::{
    AxialWeight, Chain, ChainPointLoad, ControlForce, CurrentDrag, Drag, DragWeights, Gravity,
    HarmonicForce, JointDamping, NodeDrag, PointLoads, SoilSprings, Springs, TopTension,
    VesselMotion, WaveField, WaveInertia, WaveInputs, DEFAULT_FOLD_LIMIT_DEG,
};
use crate::base::{Scalar, TipCondition};
use crate::error::{Error, ModelError, Result};
use crate::scene::{Checked, Scene, SceneInput, Support};

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Builds the model of a scene: a [`Scene`] is validated first, a
    /// [`ValidScene`](crate::ValidScene) was when it was made ([`SceneInput`]). The control node
    /// is taken from the scene's `[control]` (default: none, so no control term is computed).
    ///
    /// # Errors
    /// The scene's validation errors; [`Error::NeedsSpatialModel`] for the planar model
    /// (`DIM = 2`) of a scene with out-of-plane loads ([`Scene::is_spatial`]).
    pub fn from_scene<S: SceneInput + ?Sized>(scene: &S) -> Result<Self> {
        Self::from_checked(scene.checked()?)
    }

    /// [`Chain::from_scene`] of a scene validated already.
    pub(crate) fn from_checked(scene: Checked<'_>) -> Result<Self> {
        let scene = scene.scene();
        if DIM == 2 {
            if let Some(key) = scene.spatial_key() {
                return Err(Error::NeedsSpatialModel { key });
            }
        }
        let n = scene.n();
        let b = &scene.beam;
        let lift = |v: &[f64]| v.iter().map(|&x| D::from(x)).collect::<Vec<D>>();
        let lengths = lift(&b.lengths);
        let masses = lift(&b.masses);
        let tip = match (b.support, b.reaction_force) {
            (Support::FixedFixed | Support::PinnedPinned, false) => TipCondition::Locked,
            (Support::FixedFixed | Support::PinnedPinned, true) => TipCondition::Reaction,
            (Support::Vessel, _) => TipCondition::Prescribed,
            _ => TipCondition::Free,
        };
        // A thrust scene's control is the thrust on the vessel, not a force on the riser.
        let control_node = scene
            .control
            .as_ref()
            .map(|c| c.node)
            .filter(|_| scene.thrust().is_none());
        if let (TipCondition::Reaction, Some(c)) = (tip, control_node) {
            if c != n {
                return Err(ModelError::ReactionTipControlNode { node: c, n }.into());
            }
        }
        let springs = Self::springs_of(scene);
        let has_base = springs.present[0];
        let joint_damping = b
            .joint_damping
            .iter()
            .any(|&c| c > 0.0)
            .then(|| JointDamping {
                c: lift(&b.joint_damping),
                present: springs.present.clone(),
            });
        let loads = Self::point_loads(scene);
        let waves = Self::wave_field(scene)?;
        let vessel = Self::vessel_motion(scene, waves.as_ref().map(|w| w.shared_sea()))?;
        let (node_drag, water_drag) = Self::node_drag_of(scene, waves.as_ref(), &lengths, &masses);
        Ok(Chain {
            n,
            inv_lengths: lengths.iter().map(|l| l.recip()).collect(),
            inv_masses: masses.iter().map(|m| m.recip()).collect(),
            moment_stiffness: D::from(if has_base { b.base_stiffness } else { 0.0 }),
            tip,
            springs,
            loads: (!loads.is_empty()).then(|| PointLoads::new(loads, lengths.clone())),
            gravity: (scene.loads.gravity != 0.0).then(|| Gravity {
                g: D::from(scene.loads.gravity),
                lengths: lengths.clone(),
                masses: masses.clone(),
            }),
            tension: (scene.loads.tension != 0.0).then(|| TopTension {
                tension: D::from(scene.loads.tension),
                lengths: lengths.clone(),
            }),
            axial_weight: Self::axial_weight_of(scene, &lengths),
            control: control_node.map(|node| ControlForce {
                node,
                lengths: lengths.clone(),
            }),
            control_x: Vec::new(),
            drag: (scene.loads.drag > 0.0 && !water_drag && node_drag.is_none()).then(|| Drag {
                d: D::from(scene.loads.drag),
                weights: DragWeights::new(scene.drag_weights()),
            }),
            current: water_drag.then(|| {
                let c = scene.loads.current.as_ref();
                let d = D::from(scene.loads.drag);
                let w = DragWeights::new(scene.drag_weights());
                let mudline = scene.mudline();
                CurrentDrag::new(c, waves.clone(), d, w, (&lengths, &masses), mudline)
            }),
            wave_inertia: waves.map(WaveInertia::new),
            wave_inertia_tangent: None,
            joint_damping,
            node_drag,
            vessel_offset: D::from(vessel.as_ref().map_or(0.0, |v| v.vessel().offset)),
            vessel,
            soil: scene
                .soil
                .as_ref()
                .map(|s| SoilSprings::new(s, s.lumping(&b.lengths), &lengths))
                .filter(|s| s.last > 0),
            lengths,
            masses,
            initial: scene.time.initial,
            start: None,
        })
    }

    /// Morison's drag node by node ([`NodeDrag`]) of a `[pipe]` or `[stackup]` with
    /// `drag_model = "morison"`: ½ ρ C_d D |v_r⊥| v_r⊥ per cell on each node's velocity relative
    /// to the water (the current and the waves); and whether the thesis's momentum drag acts
    /// relative to the water instead ([`CurrentDrag`]: no Morison drag, and a current or waves
    /// with `loads.drag` > 0).
    fn node_drag_of(
        scene: &Scene,
        waves: Option<&std::sync::Arc<WaveField>>,
        lengths: &[D],
        masses: &[D],
    ) -> (Option<NodeDrag<D, DIM>>, bool) {
        let b = &scene.beam;
        let node_morison = scene
            .pipe
            .filter(|p| p.drag_model == crate::scene::DragModel::Morison);
        // A stack-up's Morison drag: each node's own coefficient from its segments and bodies.
        let stackup_morison = scene
            .stackup
            .as_ref()
            .filter(|st| st.drag_model == crate::scene::DragModel::Morison)
            .filter(|st| st.layout.node_drag.len() == scene.n());
        let morison = node_morison.is_some() || stackup_morison.is_some();
        let water_drag = !morison
            && (scene.loads.current.is_some() || (waves.is_some() && scene.loads.drag > 0.0));
        let water = || {
            CurrentDrag::new(
                scene.loads.current.as_ref(),
                waves.cloned(),
                D::zero(),
                DragWeights::new(None),
                (lengths, masses),
                scene.mudline(),
            )
        };
        let node_drag = match (node_morison, stackup_morison) {
            (Some(pipe), _) => Some(NodeDrag::new(
                pipe.drag_coefficient,
                0.5 * scene.water.density * pipe.outer_diameter,
                &b.lengths,
                &b.masses,
                water(),
            )),
            (None, Some(st)) => Some(NodeDrag::from_node_coefficients(
                &st.layout.node_drag,
                &b.masses,
                water(),
            )),
            (None, None) => None,
        };
        (node_drag, water_drag)
    }

    /// The vessel's motion of the top for `support = "vessel"` ([`VesselMotion`]; the scene is
    /// valid): the `[vessel]` table (a vessel at rest when absent) with its RAO applied to the
    /// scene's sea, realised on the scene's grid for the run.
    /// `shared` is the waves' field's sea when the chain has one (the same realisation: it is
    /// not built twice).
    fn vessel_motion(
        scene: &Scene,
        shared: Option<std::sync::Arc<crate::ocean::Sea>>,
    ) -> Result<Option<std::sync::Arc<VesselMotion>>> {
        if scene.beam.support != Support::Vessel {
            return Ok(None);
        }
        let vessel = scene.vessel.clone().unwrap_or_default();
        let t = scene.time;
        let sea = match (&scene.loads.waves, &vessel.rao) {
            (Some(w), Some(_)) => {
                let sea = match shared {
                    Some(sea) => sea,
                    None => {
                        let spec = w.sea_spec(scene.wave_depth())?;
                        let err = |e| Error::from(crate::scene::sea_error(e, w.components));
                        let sea = crate::ocean::Sea::new(&spec, t.step, t.steps as f64 * t.step)
                            .map_err(err)?;
                        std::sync::Arc::new(sea)
                    }
                };
                Some((sea, w.unit_direction()[1]))
            }
            _ => None,
        };
        let motion = VesselMotion::new(&vessel, sea, t.steps + 1)
            .map_err(|e| Error::from(crate::scene::sea_error(e, None)))?
            .holding_offset(t.initial == crate::scene::Initial::Static);
        Ok(Some(std::sync::Arc::new(motion)))
    }

    /// The axial weight of a scene: `[loads] axial_weight` (w on every node's cell), or the
    /// stack-up's own per-node weights; `None` when it has none.
    fn axial_weight_of(scene: &Scene, lengths: &[D]) -> Option<AxialWeight<D>> {
        let node_weights: Vec<D> = scene
            .stackup
            .as_ref()
            .filter(|st| st.layout.node_weights.len() == scene.n())
            .map_or_else(Vec::new, |st| {
                st.layout.node_weights.iter().map(|&w| D::from(w)).collect()
            });
        let some = scene.loads.axial_weight != 0.0 || node_weights.iter().any(|w| w.re() != 0.0);
        some.then(|| AxialWeight {
            weight: D::from(scene.loads.axial_weight),
            lengths: lengths.to_vec(),
            node_weights,
        })
    }

    /// The scene's point loads `[[loads.point]]` as model terms (their directions normalised).
    fn point_loads(scene: &Scene) -> Vec<ChainPointLoad<D>> {
        scene
            .loads
            .points
            .iter()
            .enumerate()
            .map(|(i, pl)| {
                let norm = pl.direction[0].hypot(pl.direction[1]);
                ChainPointLoad {
                    node: pl.node,
                    force: D::from(pl.force),
                    force_x: D::from(pl.force_x),
                    start: pl.start,
                    end: pl.end.unwrap_or(f64::INFINITY),
                    ramp: pl.ramp,
                    direction: [pl.direction[0] / norm, pl.direction[1] / norm],
                    harmonics: pl
                        .harmonics
                        .iter()
                        .map(|h| HarmonicForce {
                            amplitude: D::from(h.amplitude),
                            period: h.period,
                            phase: D::from(h.phase),
                        })
                        .collect(),
                    series: pl.series.as_ref().map(|s| s.samples.as_slice().into()),
                    scene_index: i,
                }
            })
            .collect()
    }

    /// The waves' field of a scene with `[loads.waves]` ([`WaveField`]; the scene is valid):
    /// its sea realised on the scene's grid, the pipe's inertia coefficient
    /// ρ_w (1 + C_a) A_o and the nodes' masses.
    fn wave_field(scene: &Scene) -> Result<Option<std::sync::Arc<WaveField>>> {
        let Some(w) = &scene.loads.waves else {
            return Ok(None);
        };
        let (inertia_per_length, node_inertia) = match (&scene.pipe, &scene.stackup) {
            (Some(pipe), _) => (
                scene.water.density * (1.0 + pipe.added_mass_coefficient) * pipe.outer_area(),
                None,
            ),
            (None, Some(st)) if st.layout.node_inertia.len() == scene.n() => {
                (0.0, Some(st.layout.node_inertia.clone()))
            }
            _ => return Ok(None),
        };
        let spec = w.sea_spec(scene.wave_depth())?;
        let t = scene.time;
        let err = |e| Error::from(crate::scene::sea_error(e, w.components));
        let sea = crate::ocean::Sea::new(&spec, t.step, t.steps as f64 * t.step).map_err(err)?;
        // The record every r steps (`record_step` = r h): ⌈N/r⌉ + 1 times cover t_N.
        let every = w.record_stride(t.step)?;
        let inputs = WaveInputs {
            lengths: scene.beam.lengths.clone(),
            masses: scene.beam.masses.clone(),
            inertia_per_length,
            direction: w.unit_direction(),
            rows: t.steps.div_ceil(every) + 1,
            every,
            cell_average: w.lumping == crate::scene::WaveLumping::Cell,
            mudline: scene.mudline(),
            node_inertia,
        };
        let field = WaveField::new(std::sync::Arc::new(sea), inputs).map_err(err)?;
        Ok(Some(std::sync::Arc::new(field)))
    }

    /// The springs a scene's support has (docs/conventions.md): interior k₂..kₙ always, k₁ except for
    /// pinned-pinned, k_{n+1} for riser and fixed-fixed.
    fn springs_of(scene: &Scene) -> Springs<D> {
        let n = scene.n();
        let b = &scene.beam;
        let mut k = vec![D::zero(); n + 1];
        let mut present = vec![false; n + 1];
        for i in 1..n {
            k[i] = D::from(b.stiffness[i - 1]);
            present[i] = true;
        }
        let (base, tip) = b.support.end_springs();
        if base {
            k[0] = D::from(b.base_stiffness);
            present[0] = true;
        }
        if tip {
            k[n] = D::from(b.tip_stiffness);
            present[n] = true;
        }
        Springs {
            k,
            present,
            fold_cos: DEFAULT_FOLD_LIMIT_DEG.to_radians().cos(),
        }
    }

    /// The same model over another scalar type (parameters lifted with `D2::from` of their real
    /// parts).
    pub fn lift<D2: Scalar>(&self) -> Chain<D2, DIM> {
        let l = |v: &[D]| v.iter().map(|x| D2::from(x.re())).collect::<Vec<D2>>();
        Chain {
            n: self.n,
            lengths: l(&self.lengths),
            masses: l(&self.masses),
            inv_lengths: l(&self.inv_lengths),
            inv_masses: l(&self.inv_masses),
            moment_stiffness: D2::from(self.moment_stiffness.re()),
            tip: self.tip,
            springs: self.springs.lift(),
            loads: self.loads.as_ref().map(|t| t.lift()),
            gravity: self.gravity.as_ref().map(|t| t.lift()),
            tension: self.tension.as_ref().map(|t| t.lift()),
            axial_weight: self.axial_weight.as_ref().map(|t| t.lift()),
            control: self.control.as_ref().map(|t| t.lift()),
            control_x: self.control_x.iter().map(|x| D2::from(x.re())).collect(),
            drag: self.drag.as_ref().map(|t| t.lift()),
            current: self.current.as_ref().map(|t| t.lift()),
            wave_inertia: self.wave_inertia.clone(),
            // A derivative part: the real parts' model has none.
            wave_inertia_tangent: None,
            joint_damping: self.joint_damping.as_ref().map(|t| t.lift()),
            node_drag: self.node_drag.as_ref().map(|t| t.lift()),
            vessel: self.vessel.clone(),
            vessel_offset: D2::from(self.vessel_offset.re()),
            soil: self.soil.as_ref().map(|t| t.lift()),
            initial: self.initial,
            start: self.start.clone(),
        }
    }
}
