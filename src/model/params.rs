//! The physical parameters θ of a [`Chain`] ([`Parameter`]): setting one (seeded with a dual
//! number for forward-mode derivatives) and asking whether the model has it.

use super::{Chain, DissipativeTerm};
use crate::base::{Parameter, Scalar};
use crate::error::{Error, Result};

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Sets a physical parameter (see [`Parameter`]); seed it with a dual number to obtain
    /// forward-mode derivatives of a whole simulation with respect to it.
    pub fn set_parameter(&mut self, p: Parameter, value: D) -> Result<()> {
        let n = self.n;
        // A tabulated water momentum ([`Chain::tabulate_water`]) may read the parameter.
        if let Some(nd) = &mut self.node_drag {
            nd.clear_water_table();
        }
        match p {
            Parameter::InteriorStiffness => (1..n).for_each(|i| self.springs.k[i] = value),
            Parameter::JointStiffness(j) => self.set_joint_spring(p, j, value)?,
            Parameter::BaseStiffness => self.set_end_spring(p, 0, value)?,
            Parameter::TipStiffness => self.set_end_spring(p, n, value)?,
            Parameter::Mass if self.node_drag.is_some() => {
                return Err(missing(
                    p,
                    "the node-by-node Morison drag's constants depend on the masses node by node",
                ));
            }
            Parameter::DragCoefficient => match &mut self.node_drag {
                Some(d) => d.cd = value,
                None => {
                    return Err(missing(
                        p,
                        "the scene has no node-by-node Morison drag (`[pipe] drag_model`)",
                    ))
                }
            },
            Parameter::Mass => self.set_uniform_mass(value)?,
            Parameter::Drag => match (&mut self.drag, &mut self.current) {
                (Some(d), _) => d.d = value,
                (None, Some(c)) => c.d = value,
                (None, None) => return Err(missing(p, "the scene has no drag (D = 0)")),
            },
            Parameter::Tension => match &mut self.tension {
                Some(t) => t.tension = value,
                None => return Err(missing(p, "the scene has no tension (T = 0)")),
            },
            Parameter::AxialWeight => match &mut self.axial_weight {
                Some(t) if !t.node_weights.is_empty() => {
                    return Err(missing(p, "a stack-up's weights have no single w"))
                }
                Some(t) => t.weight = value,
                None => return Err(missing(p, "the scene has no axial weight (w = 0)")),
            },
            Parameter::JointDamping => match &mut self.joint_damping {
                Some(j) => {
                    for (c, &on) in j.c.iter_mut().zip(&j.present) {
                        if on {
                            *c = value;
                        }
                    }
                }
                None => return Err(missing(p, "the scene has no joint damping")),
            },
            Parameter::CurrentSpeed if self.node_drag.is_some() => {
                match self.node_drag.as_mut().map(|d| &mut d.water) {
                    Some(c) if c.has_parameter(p) => c.speed = value,
                    _ => return Err(missing(p, "the scene has no current with a speed")),
                }
            }
            Parameter::VesselOffset => {
                if self.vessel.is_none() {
                    return Err(missing(
                        p,
                        "the top is not held by a vessel (support = \"vessel\")",
                    ));
                }
                self.vessel_offset = value;
            }
            Parameter::SoilModulus => match &mut self.soil {
                Some(s) => s.modulus = value,
                None => return Err(missing(p, "the scene has no node in the soil")),
            },
            Parameter::CurrentSpeed => match &mut self.current {
                Some(c) if c.has_parameter(p) => c.speed = value,
                Some(_) => return Err(missing(p, "a table profile has no single speed")),
                None => return Err(missing(p, "the scene has no current")),
            },
            Parameter::LoadForce(i)
            | Parameter::LoadForceX(i)
            | Parameter::LoadAmplitude { load: i, .. }
            | Parameter::LoadPhase { load: i, .. } => self.set_load_parameter(p, i, value)?,
        }
        Ok(())
    }

    /// [`Chain::set_parameter`] of interior joint j's spring.
    fn set_joint_spring(&mut self, p: Parameter, j: usize, value: D) -> Result<()> {
        if !(1..self.n).contains(&j) || !self.springs.present[j] {
            return Err(missing(
                p,
                "no interior joint with a spring there (1 ≤ j ≤ n − 1; the end springs are \
                 BaseStiffness and TipStiffness)",
            ));
        }
        self.springs.k[j] = value;
        Ok(())
    }

    /// [`Chain::set_parameter`] of an end's spring, joint `end` = 0 (the base, whose stiffness
    /// is also the moment's) or n (the tip).
    fn set_end_spring(&mut self, p: Parameter, end: usize, value: D) -> Result<()> {
        if !self.springs.present[end] {
            let reason = if end == 0 {
                "the support has no base spring"
            } else {
                "the support has no tip spring"
            };
            return Err(missing(p, reason));
        }
        self.springs.k[end] = value;
        if end == 0 {
            self.moment_stiffness = value;
        }
        Ok(())
    }

    /// [`Chain::set_parameter`] of the uniform mass m: every node's, gravity's, and the
    /// quantities built from the masses (the current's drag weights and water momentum, the
    /// inverse masses).
    fn set_uniform_mass(&mut self, value: D) -> Result<()> {
        self.masses.iter_mut().for_each(|m| *m = value);
        if let Some(g) = &mut self.gravity {
            g.masses.iter_mut().for_each(|m| *m = value);
        }
        if let Some(c) = &mut self.current {
            c.refresh(&self.lengths, &self.masses)
                .map_err(|e| crate::scene::sea_error(e, None))?;
            c.weights.refresh(&self.lengths, &self.masses);
        }
        if let Some(d) = &mut self.drag {
            d.weights.refresh(&self.lengths, &self.masses);
        }
        self.refresh_inverses();
        Ok(())
    }

    /// [`Chain::set_parameter`] of point load `i` (its scene index): its force (z or x), or a
    /// harmonic's amplitude or phase.
    fn set_load_parameter(&mut self, p: Parameter, i: usize, value: D) -> Result<()> {
        if !self.has_parameter(p) {
            return Err(missing(
                p,
                "no such point load or harmonic (F_x: only in the spatial model)",
            ));
        }
        let l = self.loads.as_mut().and_then(|ls| ls.by_scene_index(i));
        if let Some(l) = l {
            match p {
                Parameter::LoadForce(_) => l.force = value,
                Parameter::LoadForceX(_) => l.force_x = value,
                Parameter::LoadAmplitude { harmonic, .. } => {
                    l.harmonics[harmonic].amplitude = value;
                }
                Parameter::LoadPhase { harmonic, .. } => {
                    l.harmonics[harmonic].phase = value;
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Whether `p` is a parameter of this model that gradients can be taken for (mass needs
    /// uniform masses, drag needs D > 0, end stiffnesses need an end spring, loads need that load,
    /// harmonic parameters that harmonic, F_x the spatial model).
    pub fn has_parameter(&self, p: Parameter) -> bool {
        match p {
            Parameter::Mass => self.has_uniform_mass() && self.node_drag.is_none(),
            Parameter::Drag => self.has_drag(),
            Parameter::DragCoefficient => self.node_drag.is_some(),
            Parameter::CurrentSpeed => match &self.node_drag {
                Some(d) => d.has_parameter(p),
                None => self.current.as_ref().is_some_and(|c| c.has_parameter(p)),
            },
            Parameter::BaseStiffness => self.springs.present[0],
            Parameter::TipStiffness => self.springs.present[self.n],
            Parameter::InteriorStiffness => true,
            Parameter::JointStiffness(j) => (1..self.n).contains(&j) && self.springs.present[j],
            Parameter::Tension => self.tension.is_some(),
            Parameter::JointDamping => self.joint_damping.as_ref().is_some_and(|j| j.is_uniform()),
            Parameter::AxialWeight => self
                .axial_weight
                .as_ref()
                .is_some_and(|t| t.node_weights.is_empty()),
            Parameter::SoilModulus => self.soil.is_some(),
            Parameter::VesselOffset => self.vessel.is_some(),
            Parameter::LoadForce(_)
            | Parameter::LoadForceX(_)
            | Parameter::LoadAmplitude { .. }
            | Parameter::LoadPhase { .. } => {
                self.loads.as_ref().is_some_and(|ls| ls.reads(p, DIM == 3))
            }
        }
    }

    /// Whether all masses are equal (parameter derivatives with respect to [`Parameter::Mass`]
    /// are taken at a common mass).
    pub fn has_uniform_mass(&self) -> bool {
        let m0 = self.masses[0].re();
        self.masses
            .iter()
            .all(|m| (m.re() - m0).abs() <= 1e-15 * m0.abs())
    }

    /// Recomputes 1/lᵢ and 1/mᵢ after the masses changed.
    fn refresh_inverses(&mut self) {
        for i in 0..self.n {
            self.inv_lengths[i] = self.lengths[i].recip();
            self.inv_masses[i] = self.masses[i].recip();
        }
    }
}

/// The error for a parameter the model does not have, with the reason.
fn missing(parameter: Parameter, reason: &'static str) -> Error {
    Error::NoSuchParameter { parameter, reason }
}
