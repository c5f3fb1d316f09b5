//! The persistent per-triangle-pair workspace of cbvh's manifold queries,
//! so that rapier warm-starts contacts as it does for parry's meshes.

use crate::hash::FastMap;
use parry3d::query::{
    ContactManifold, ContactManifoldsWorkspace, TypedWorkspaceData, WorkspaceData,
};

/// Where a sub-pair's manifold sits, and whether it was seen this step.
#[derive(Clone, Copy)]
struct SubDetector {
    manifold_id: usize,
    timestamp: bool,
}

/// Manifold bookkeeping keyed by `(part of shape 1, part of shape 2)`.
#[derive(Clone, Default)]
pub struct CbvhWorkspace {
    timestamp: bool,
    sub_detectors: FastMap<(u32, u32), SubDetector>,
}

impl WorkspaceData for CbvhWorkspace {
    fn as_typed_workspace_data(&self) -> TypedWorkspaceData<'_> {
        TypedWorkspaceData::Custom
    }

    fn clone_dyn(&self) -> Box<dyn WorkspaceData> {
        Box::new(self.clone())
    }
}

/// One step of manifold updates: keeps last step's manifolds for pairs seen
/// again and drops the rest when finished.
pub struct ManifoldUpdate<'a, M, C> {
    ws: &'a mut CbvhWorkspace,
    old: Vec<ContactManifold<M, C>>,
    manifolds: &'a mut Vec<ContactManifold<M, C>>,
    stamp: bool,
}

impl<'a, M: Default + Clone, C: Default + Copy> ManifoldUpdate<'a, M, C> {
    /// Starts a step over `manifolds` with `workspace` (created if absent or
    /// of another type).
    pub fn begin(
        workspace: &'a mut Option<ContactManifoldsWorkspace>,
        manifolds: &'a mut Vec<ContactManifold<M, C>>,
    ) -> Self {
        let ok = workspace
            .as_ref()
            .is_some_and(|w| w.0.downcast_ref::<CbvhWorkspace>().is_some());
        if !ok {
            *workspace = Some(ContactManifoldsWorkspace(
                Box::new(CbvhWorkspace::default()),
            ));
        }
        let ws: &mut CbvhWorkspace = workspace
            .as_mut()
            .and_then(|w| w.0.downcast_mut())
            .expect("workspace was just set to a CbvhWorkspace");
        ws.timestamp = !ws.timestamp;
        let stamp = ws.timestamp;
        let old = std::mem::take(manifolds);
        Self {
            ws,
            old,
            manifolds,
            stamp,
        }
    }

    /// The manifold of the pair `(part1, part2)`: last step's if it had one,
    /// else a fresh one.
    pub fn manifold(&mut self, part1: u32, part2: u32) -> &mut ContactManifold<M, C> {
        let id = self.manifolds.len();
        match self.ws.sub_detectors.entry((part1, part2)) {
            std::collections::hash_map::Entry::Occupied(e) => {
                let sd = e.into_mut();
                let m = self.old[sd.manifold_id].take();
                sd.manifold_id = id;
                sd.timestamp = self.stamp;
                self.manifolds.push(m);
            }
            std::collections::hash_map::Entry::Vacant(e) => {
                let mut m = ContactManifold::new();
                m.subshape1 = part1;
                m.subshape2 = part2;
                self.manifolds.push(m);
                e.insert(SubDetector {
                    manifold_id: id,
                    timestamp: self.stamp,
                });
            }
        }
        &mut self.manifolds[id]
    }
}

impl<M, C> ManifoldUpdate<'_, M, C> {
    /// The manifolds handed out this step, in the order they were asked for.
    pub fn manifolds_mut(&mut self) -> &mut [ContactManifold<M, C>] {
        self.manifolds
    }
}

impl<M, C> Drop for ManifoldUpdate<'_, M, C> {
    fn drop(&mut self) {
        let stamp = self.stamp;
        self.ws.sub_detectors.retain(|_, d| d.timestamp == stamp);
    }
}
