//! A per-step trace of one body in a [`super::slide`] scene: its energy
//! (kinetic, translational and rotational, and potential) and the contacts
//! rapier solved it with (points, normals, depths, feature ids, impulses),
//! to find where a scene's energy goes: contact points jumping from step to
//! step, feature ids that change (rapier warm-starts a point only from last
//! step's point with the same ids), speculative points that act too early.
//!
//! [`Scene::run_traced`](super::slide::Scene::run_traced) fills a
//! [`Trace`]; the example `rapier_slide --trace DIR` writes it as two CSV
//! files per run ([`Trace::steps_csv`], [`Trace::contacts_csv`]).

use std::collections::HashSet;
use std::fmt::Write as _;

use parry3d::math::Vector;
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle};

/// One contact point the solver saw at a step, in world coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TracePoint {
    /// Index of its manifold among the pair's solver manifolds.
    pub manifold: u32,
    /// The manifold's subshapes (parry's shape 1, shape 2).
    pub subshapes: (u32, u32),
    /// The point's feature ids on shape 1 and shape 2 (packed, as parry
    /// stores them); `(0, 0)` for a cluster point whose ids rapier dropped.
    pub fids: (u32, u32),
    /// The point on shape 1, in the world.
    pub point: [f32; 3],
    /// The manifold's normal (from shape 1 to shape 2), in the world.
    pub normal: [f32; 3],
    /// Signed distance (negative: penetration).
    pub dist: f32,
    /// The normal impulse the solver applied at the step.
    pub impulse: f32,
    /// The friction impulse's magnitude.
    pub tangent_impulse: f32,
    /// Whether rapier made a solver contact of it (within the prediction
    /// distance, or closing within the step).
    pub solved: bool,
}

/// One step of a traced body.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TraceStep {
    /// Time after the step (s).
    pub t: f32,
    /// Translational kinetic energy (J).
    pub kinetic_linear: f32,
    /// Rotational kinetic energy (J).
    pub kinetic_angular: f32,
    /// Potential energy relative to the start (J).
    pub potential: f32,
    /// Speed of the centre of mass (m/s).
    pub speed: f32,
    /// Angular speed (rad/s).
    pub angular_speed: f32,
    /// Manifolds the narrow phase produced for the body's pairs.
    pub manifolds: u32,
    /// Manifolds the solver saw (rapier's clusters, when it clustered).
    pub solver_manifolds: u32,
    /// The points of the solver manifolds.
    pub points: Vec<TracePoint>,
}

impl TraceStep {
    /// Kinetic plus potential energy (J).
    pub fn energy(&self) -> f32 {
        self.kinetic_linear + self.kinetic_angular + self.potential
    }

    /// The narrow phase's feature-id pairs of the points, with their
    /// subshapes.
    fn ids(&self) -> HashSet<(u32, u32, u32, u32)> {
        self.points
            .iter()
            .map(|p| (p.subshapes.0, p.subshapes.1, p.fids.0, p.fids.1))
            .collect()
    }
}

/// The trace of one body over a run (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Trace {
    /// The body's mass (kg).
    pub mass: f32,
    /// One entry per step, in order.
    pub steps: Vec<TraceStep>,
}

/// What a trace says in a few numbers ([`Trace::summary`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TraceSummary {
    /// Energy at the first step minus at the last (J; positive: lost).
    pub energy_lost: f32,
    /// The same as a fraction of the potential energy released.
    pub lost_fraction: f32,
    /// Steps whose energy dropped by more than 0.1 % of the energy
    /// released so far (impacts).
    pub drops: u32,
    /// Mean solver points per step.
    pub mean_points: f32,
    /// Mean fraction of a step's points whose feature ids (and subshapes)
    /// the previous step had too.
    pub ids_kept: f32,
    /// Mean normal impulse of a step, summed over its points (N s).
    pub mean_impulse: f32,
}

impl Trace {
    /// Appends the state of `body` (its colliders' contacts with everything)
    /// after a step ending at time `t`, its potential energy measured from
    /// `y0` (the centre of mass's starting height) under `gravity`.
    pub fn record(
        &mut self,
        world: &PhysicsWorld,
        body: RigidBodyHandle,
        t: f32,
        y0: f32,
        gravity: f32,
    ) {
        let b = &world.bodies[body];
        let m = b.mass();
        self.mass = m;
        let v = b.linvel();
        let w = b.angvel();
        let mprops = b.mass_properties().local_mprops;
        let com = b.position().transform_point(mprops.local_com);
        // ω · I ω in the body's frame.
        let wl = b.rotation().inverse() * w;
        let iw = mprops.reconstruct_inertia_matrix() * wl;
        let mut step = TraceStep {
            t,
            kinetic_linear: 0.5 * m * v.length_squared(),
            kinetic_angular: 0.5 * wl.dot(iw),
            potential: m * gravity * (com.y - y0),
            speed: v.length(),
            angular_speed: w.length(),
            ..Default::default()
        };
        let colliders: Vec<ColliderHandle> = b.colliders().to_vec();
        for c in colliders {
            for pair in world.narrow_phase.contact_pairs_with(c) {
                step.manifolds += pair.manifolds().len() as u32;
                let pos1 = world.colliders[pair.collider1].position();
                let solver = pair.solver_manifolds();
                step.solver_manifolds += solver.len() as u32;
                for (k, m) in solver.iter().enumerate() {
                    let normal = m.data.normal;
                    for (pi, p) in m.points.iter().enumerate() {
                        let solved = m.data.solver_contacts.iter().any(|sc| {
                            (sc.contact_id[0] & !rapier3d::geometry::NEW_CONTACT_BIT) as usize == pi
                        });
                        let point = pos1.transform_point(p.local_p1);
                        step.points.push(TracePoint {
                            manifold: k as u32,
                            subshapes: (m.subshape1, m.subshape2),
                            fids: (p.fid1.0, p.fid2.0),
                            point: point.to_array(),
                            normal: normal.to_array(),
                            dist: p.dist,
                            impulse: p.data.impulse,
                            tangent_impulse: p.data.tangent_impulse.norm(),
                            solved,
                        });
                    }
                }
            }
        }
        self.steps.push(step);
    }

    /// The trace in a few numbers.
    pub fn summary(&self) -> TraceSummary {
        let n = self.steps.len();
        if n < 2 {
            return TraceSummary::default();
        }
        let (first, last) = (&self.steps[0], &self.steps[n - 1]);
        let energy_lost = first.energy() - last.energy();
        let released = (first.potential - last.potential).max(f32::MIN_POSITIVE);
        let mut drops = 0;
        let mut kept = 0.0f32;
        for w in self.steps.windows(2) {
            let so_far = (self.steps[0].potential - w[1].potential).max(f32::MIN_POSITIVE);
            if w[0].energy() - w[1].energy() > 1e-3 * so_far {
                drops += 1;
            }
            let (a, b) = (w[0].ids(), w[1].ids());
            kept += if b.is_empty() {
                1.0
            } else {
                b.intersection(&a).count() as f32 / b.len() as f32
            };
        }
        TraceSummary {
            energy_lost,
            lost_fraction: energy_lost / released,
            drops,
            mean_points: self
                .steps
                .iter()
                .map(|s| s.points.len() as f32)
                .sum::<f32>()
                / n as f32,
            ids_kept: kept / (n - 1) as f32,
            mean_impulse: self
                .steps
                .iter()
                .map(|s| s.points.iter().map(|p| p.impulse).sum::<f32>())
                .sum::<f32>()
                / n as f32,
        }
    }

    /// One line per step: time, energies, speeds, manifold and point
    /// counts, the fraction of points whose ids the last step had, the
    /// summed normal impulse and the deepest point's distance.
    pub fn steps_csv(&self) -> String {
        let mut s = String::from(
            "step,t,ke_lin,ke_rot,pe,energy,speed,angspeed,manifolds,solver_manifolds,points,solved,ids_kept,impulse,deepest\n",
        );
        let mut last: Option<HashSet<(u32, u32, u32, u32)>> = None;
        for (k, st) in self.steps.iter().enumerate() {
            let ids = st.ids();
            let kept = match &last {
                Some(a) if !ids.is_empty() => ids.intersection(a).count() as f32 / ids.len() as f32,
                _ => f32::NAN,
            };
            let deepest = st
                .points
                .iter()
                .map(|p| p.dist)
                .fold(f32::INFINITY, f32::min);
            let _ = writeln!(
                s,
                "{k},{:.5},{:.6},{:.6},{:.6},{:.6},{:.5},{:.5},{},{},{},{},{:.3},{:.6},{:.6}",
                st.t,
                st.kinetic_linear,
                st.kinetic_angular,
                st.potential,
                st.energy(),
                st.speed,
                st.angular_speed,
                st.manifolds,
                st.solver_manifolds,
                st.points.len(),
                st.points.iter().filter(|p| p.solved).count(),
                kept,
                st.points.iter().map(|p| p.impulse).sum::<f32>(),
                deepest,
            );
            last = Some(ids);
        }
        s
    }

    /// One line per contact point and step.
    pub fn contacts_csv(&self) -> String {
        let mut s = String::from(
            "step,t,manifold,sub1,sub2,fid1,fid2,px,py,pz,nx,ny,nz,dist,impulse,tangent,solved\n",
        );
        for (k, st) in self.steps.iter().enumerate() {
            for p in &st.points {
                let _ = writeln!(
                    s,
                    "{k},{:.5},{},{},{},{:#x},{:#x},{:.6},{:.6},{:.6},{:.5},{:.5},{:.5},{:.6},{:.6},{:.6},{}",
                    st.t,
                    p.manifold,
                    p.subshapes.0,
                    p.subshapes.1,
                    p.fids.0,
                    p.fids.1,
                    p.point[0],
                    p.point[1],
                    p.point[2],
                    p.normal[0],
                    p.normal[1],
                    p.normal[2],
                    p.dist,
                    p.impulse,
                    p.tangent_impulse,
                    u8::from(p.solved),
                );
            }
        }
        s
    }
}

/// The body's centre of mass height (the potential energy's origin).
pub(crate) fn com_height(world: &PhysicsWorld, body: RigidBodyHandle) -> f32 {
    let b = &world.bodies[body];
    let c: Vector = b
        .position()
        .transform_point(b.mass_properties().local_mprops.local_com);
    c.y
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(ke: f32, pe: f32, ids: &[u32]) -> TraceStep {
        TraceStep {
            kinetic_linear: ke,
            potential: pe,
            points: ids
                .iter()
                .map(|&i| TracePoint {
                    fids: (i, i),
                    impulse: 0.5,
                    ..Default::default()
                })
                .collect(),
            ..Default::default()
        }
    }

    #[test]
    fn summary_counts_the_lost_energy_drops_and_kept_ids() {
        // 3 J released; 0.6 J of it lost, all at the third step.
        let trace = Trace {
            mass: 1.0,
            steps: vec![
                step(0.0, 0.0, &[1, 2]),
                step(1.0, -1.0, &[2, 3]),
                step(1.4, -2.0, &[2, 3]),
                step(2.4, -3.0, &[4, 5]),
            ],
        };
        let s = trace.summary();
        assert!((s.energy_lost - 0.6).abs() < 1e-6, "{s:?}");
        assert!((s.lost_fraction - 0.2).abs() < 1e-6, "{s:?}");
        assert_eq!(s.drops, 1, "{s:?}");
        // Kept: half, all, none.
        assert!((s.ids_kept - 0.5).abs() < 1e-6, "{s:?}");
        assert_eq!(s.mean_points, 2.0);
        assert!((s.mean_impulse - 1.0).abs() < 1e-6, "{s:?}");
        let csv = trace.steps_csv();
        assert_eq!(csv.lines().count(), 5);
        assert!(
            csv.lines().nth(3).is_some_and(|l| l.contains(",1.000,")),
            "{csv}"
        );
        assert_eq!(trace.contacts_csv().lines().count(), 9);
    }
}
