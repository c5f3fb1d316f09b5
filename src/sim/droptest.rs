//! The drop test behind the sims: a dynamic mesh dropped onto a fixed mesh
//! in rapier, once per shape kind, from the same initial conditions, with
//! the narrow phase timed per step (see [`super::timed::Timed`]). The shape
//! kinds are parry's `TriMesh` and every codec of the registry
//! ([`CodecKind`]).

use std::str::FromStr;
use std::sync::atomic::Ordering;
use std::time::Instant;

use parry3d::math::{Pose as PPose, Vector};
use parry3d::query::{DefaultQueryDispatcher, PersistentQueryDispatcher};
use parry3d::shape::{Shape, SharedShape, TriMeshFlags};
use rapier3d::geometry::{ContactData, ContactManifoldData};
use rapier3d::prelude::{
    ColliderBuilder, ColliderHandle, NarrowPhase, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle,
};

use super::timed::{Timed, shape_address};
use crate::build::BuildOptions;
use crate::codec::{AnyCodec, AnyOptions, CacheStats, CodecKind, OpenOptions};
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;
use crate::parry::cbvh_cbvh::interference;
use crate::parry::trimesh::{parry_trimesh, trimesh_bytes_by_part, trimesh_interference};
use crate::parry::{CbvhShape, ContactCounters, ContactMode, Dispatcher};

/// Which collision shape a run uses for both meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeKind {
    /// parry's own `TriMesh`, with parry's default dispatcher: the baseline
    /// (`parry`).
    Parry,
    /// parry's `TriMesh` with `TriMeshFlags::FIX_INTERNAL_EDGES` on both
    /// meshes (`parry-fixed`): parry's own internal-edge handling, the
    /// reference for contacts in motion. Not in [`ShapeKind::all`] (not a
    /// timing baseline); name it in `--shapes`.
    ParryFixed,
    /// A cbvh codec with cbvh's dispatcher, its decode cache (if it has
    /// one) holding the whole tree (named as the codec: `plain`, `racbvh`).
    Cbvh(CodecKind),
    /// A cbvh codec with a decode cache, limited to 10 % of the decoded
    /// tree (the codec's name and `-10pct`: `racbvh-10pct`). Only for
    /// codecs with a cache ([`CodecKind::has_cache`]).
    CbvhTenthCache(CodecKind),
}

impl ShapeKind {
    /// Every kind, baseline first: parry, then each codec of the registry,
    /// followed by its small-cache variant if it has a cache.
    pub fn all() -> Vec<ShapeKind> {
        let mut all = vec![ShapeKind::Parry];
        for &k in CodecKind::ALL {
            all.push(ShapeKind::Cbvh(k));
            if k.has_cache() {
                all.push(ShapeKind::CbvhTenthCache(k));
            }
        }
        all
    }

    /// The name used in `--shapes` and in reports.
    pub fn name(self) -> String {
        match self {
            ShapeKind::Parry => "parry".into(),
            ShapeKind::ParryFixed => "parry-fixed".into(),
            ShapeKind::Cbvh(k) => k.name().into(),
            ShapeKind::CbvhTenthCache(k) => format!("{}-10pct", k.name()),
        }
    }

    /// Whether this is one of parry's `TriMesh` runs (no cbvh, no contact
    /// modes).
    pub fn is_parry(self) -> bool {
        matches!(self, ShapeKind::Parry | ShapeKind::ParryFixed)
    }
}

impl FromStr for ShapeKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let mut all = ShapeKind::all();
        all.insert(1, ShapeKind::ParryFixed);
        all.iter()
            .copied()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| {
                let names: Vec<String> = all.iter().map(|k| k.name()).collect();
                format!("unknown shape {s:?}; use one of: {}", names.join(", "))
            })
    }
}

/// Two meshes, placed, and how long to simulate.
#[derive(Clone, Debug)]
pub struct DropScene {
    /// The dynamic mesh (the statue), already placed above the base.
    /// Empty when [`dropped_file`](Self::dropped_file) serves every run.
    pub dropped: Mesh,
    /// The dropped mesh's own codec file, when the statue came as one:
    /// the runs of its codec open it as it is (a model too large to build
    /// again in memory, built out of core) instead of building from
    /// [`dropped`](Self::dropped), with the whole tree cached, or a tenth
    /// of it for `-10pct`. Its coordinates are the scene's: the base is
    /// placed around it.
    pub dropped_file: Option<DroppedFile>,
    /// Metres a scene unit stands for, inverted: rapier's
    /// `IntegrationParameters::length_unit`, which scales its tolerances,
    /// and gravity (9.81 of them a second squared). 1 but for a scene
    /// scaled as a whole (a codec-file statue kept as stored, the base
    /// scaled around it by `1 / length_unit`), so that it falls as the
    /// same scene at unit scale would.
    pub length_unit: f32,
    /// The fixed mesh (the turbine).
    pub base: Mesh,
    /// Number of steps.
    pub steps: usize,
    /// Time step in seconds (1/60 by default).
    pub dt: f32,
    /// Let rapier reuse contacts of pairs that barely moved (off for
    /// timing: it skips the narrow phase).
    pub contact_recycling: bool,
    /// Each codec's options for the cbvh shapes (the runs set the cache
    /// budgets themselves).
    pub codec_options: AnyOptions,
    /// How the cbvh shapes' canonical trees are built (the sims use one
    /// triangle a leaf, as in the papers, unless `--leaf-size` says
    /// otherwise; CLBVH's leaves are its own, collapsed from that tree up to
    /// its `leaf_size`).
    pub build_options: BuildOptions,
}

/// A dropped mesh's codec file (see [`DropScene::dropped_file`]).
#[derive(Clone, Debug)]
pub struct DroppedFile {
    /// The file (already verified once).
    pub path: std::path::PathBuf,
    /// Its codec.
    pub kind: CodecKind,
    /// Its triangles.
    pub triangles: usize,
    /// Its root box.
    pub bounds: ([f32; 3], [f32; 3]),
}

impl DropScene {
    /// The dropped mesh's bounds (its file's root box when the mesh is
    /// not held).
    pub fn dropped_bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        match &self.dropped_file {
            Some(f) if self.dropped.triangles.is_empty() => Some(f.bounds),
            _ => self.dropped.bounds(),
        }
    }

    /// The dropped mesh's triangles.
    pub fn dropped_triangles(&self) -> usize {
        match &self.dropped_file {
            Some(f) => f.triangles,
            None => self.dropped.triangles.len(),
        }
    }
}

/// How to place a dropped mesh over a base mesh.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Width of the dropped mesh as a fraction of the base's width (x/z).
    pub width_fraction: f32,
    /// Gap between the dropped mesh's bottom and the base's top, as a
    /// fraction of the dropped mesh's height.
    pub gap_fraction: f32,
    /// Horizontal offset of the drop point from the base's centre, as a
    /// fraction of the base's width (x, z).
    pub offset_fraction: [f32; 2],
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            width_fraction: 0.5,
            gap_fraction: 0.05,
            offset_fraction: [0.0, 0.0],
        }
    }
}

/// Scales and moves `dropped` (any units, any offset) so that its width is
/// `width_fraction` of the base's and it hangs just above the base's top,
/// centred over it (plus the offset). Returns the scale applied.
pub fn place(dropped: &mut Mesh, base: &Mesh, p: &Placement) -> f32 {
    let (Some(d), Some(b)) = (dropped.bounds(), base.bounds()) else {
        return 1.0;
    };
    let (scale, from, target) = placement(d, b, p);
    for v in &mut dropped.vertices {
        for k in 0..3 {
            v[k] = (v[k] - from[k]) * scale + target[k];
        }
    }
    scale
}

/// [`place`] the other way round, for a dropped mesh that must stay as it
/// is (a codec file used as stored, [`DropScene::dropped_file`]): scales
/// and moves `base` so that the dropped mesh of bounds `dropped` sits on
/// it as [`place`] would have put it (the whole scene scaled by the
/// inverse). Returns the scale [`place`] would have applied to the
/// dropped mesh (the base's is its inverse).
pub fn place_base(dropped: ([f32; 3], [f32; 3]), base: &mut Mesh, p: &Placement) -> f32 {
    let Some(b) = base.bounds() else {
        return 1.0;
    };
    let (scale, from, target) = placement(dropped, b, p);
    for v in &mut base.vertices {
        for k in 0..3 {
            v[k] = (v[k] - target[k]) / scale + from[k];
        }
    }
    scale
}

/// The scale and the two anchor points of [`place`]: the dropped mesh's
/// point `from` goes to `target`, scaled by `scale` about it.
fn placement(
    (dlo, dhi): ([f32; 3], [f32; 3]),
    (blo, bhi): ([f32; 3], [f32; 3]),
    p: &Placement,
) -> (f32, [f32; 3], [f32; 3]) {
    let width = |lo: [f32; 3], hi: [f32; 3]| (hi[0] - lo[0]).max(hi[2] - lo[2]).max(1e-12);
    let scale = p.width_fraction * width(blo, bhi) / width(dlo, dhi);
    let height = (dhi[1] - dlo[1]) * scale;
    let bw = width(blo, bhi);
    let target = [
        0.5 * (blo[0] + bhi[0]) + p.offset_fraction[0] * bw,
        bhi[1] + p.gap_fraction * height,
        0.5 * (blo[2] + bhi[2]) + p.offset_fraction[1] * bw,
    ];
    let from = [0.5 * (dlo[0] + dhi[0]), dlo[1], 0.5 * (dlo[2] + dhi[2])];
    (scale, from, target)
}

/// Summary statistics of per-step times, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TimeStats {
    /// Median.
    pub median: f64,
    /// Mean.
    pub mean: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

impl TimeStats {
    /// Statistics of `ms` (zeros if empty).
    pub fn of(ms: &[f64]) -> Self {
        if ms.is_empty() {
            return Self::default();
        }
        let mut s = ms.to_vec();
        s.sort_by(f64::total_cmp);
        let q = |f: f64| s[((s.len() - 1) as f64 * f).round() as usize];
        Self {
            median: q(0.5),
            mean: s.iter().sum::<f64>() / s.len() as f64,
            p95: q(0.95),
            max: s[s.len() - 1],
        }
    }
}

/// One run of the drop test: a shape kind and, for cbvh shapes, the
/// dispatcher's contact mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSpec {
    /// The shape kind.
    pub kind: ShapeKind,
    /// The contact mode (ignored for parry's `TriMesh`).
    pub mode: ContactMode,
}

impl RunSpec {
    /// The name in reports: the shape's, with `-pairs` for cbvh shapes in
    /// the per-triangle-pair mode (`plain`, `plain-pairs`, `racbvh`, ...).
    pub fn name(&self) -> String {
        match (self.kind, self.mode) {
            (ShapeKind::Parry | ShapeKind::ParryFixed, _) | (_, ContactMode::Patches(_)) => {
                self.kind.name()
            }
            (_, ContactMode::PerTrianglePair) => format!("{}-pairs", self.kind.name()),
        }
    }

    /// Parses a run name: a shape name, optionally followed by `-pairs` or
    /// `-patches`; a bare cbvh name takes `default` as its mode.
    pub fn parse(s: &str, default: ContactMode) -> Result<RunSpec, String> {
        let s = s.trim();
        let (base, mode) = if let Some(b) = s.strip_suffix("-pairs") {
            (b, Some(ContactMode::PerTrianglePair))
        } else if let Some(b) = s.strip_suffix("-patches") {
            (b, Some(ContactMode::default()))
        } else {
            (s, None)
        };
        let kind: ShapeKind = base
            .parse()
            .map_err(|e: String| format!("{e} (optionally followed by -pairs or -patches)"))?;
        if kind.is_parry() && mode.is_some() {
            return Err(format!(
                "{s:?}: parry's TriMesh has no contact modes; use \"{}\"",
                kind.name()
            ));
        }
        Ok(RunSpec {
            kind,
            mode: mode.unwrap_or(default),
        })
    }
}

/// The peak resident memory of this process since the last
/// [`reset_peak_rss`], in bytes (Linux; `None` elsewhere).
pub fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets the peak resident memory counter (Linux: writes 5 to
/// `/proc/self/clear_refs`). Returns whether it could.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Which trajectory a run's narrow phase is timed along once more after
/// the run (see [`Trajectory`]).
#[derive(Clone, Copy, Debug)]
pub enum Replay<'a> {
    /// None.
    Off,
    /// The run's own: the first run of a comparison, whose trajectory the
    /// others follow.
    Own,
    /// Another run's.
    Along(&'a Trajectory),
}

/// The narrow phase's work in one run, step by step: every
/// `contact_manifolds` call rapier made (the relative pose, the prediction
/// distance, which collider came first) and whether the step had contact
/// points. Shapes timed along one trajectory ([`Replay`]) do the same
/// contact work, pose for pose, whatever their own runs did: two lossless
/// codecs that meet the same triangle pairs in different orders reduce
/// them to slightly different patches, and their bodies then part ways
/// within a few steps.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// The run it was recorded in (see [`RunSpec::name`]).
    pub from: String,
    steps: Vec<Vec<Call>>,
    in_contact: Vec<bool>,
}

/// One recorded `contact_manifolds` call.
#[derive(Clone, Copy, Debug)]
struct Call {
    pos12: PPose,
    prediction: f32,
    base_first: bool,
}

/// Times a trajectory is replayed by default (the sims' `--replay-rounds`);
/// each step's best time is kept.
pub const REPLAY_ROUNDS: usize = 5;

/// The narrow phase of `base` and `dropped` through `dispatcher` along
/// `t`, step by step, in milliseconds: the best of `rounds` replays (at
/// least one; [`REPLAY_ROUNDS`] by default). A step takes well under a
/// millisecond on the default scenes, where one timing is at the mercy of
/// an interrupt or a busy neighbour on a shared machine; the best of
/// several is the step's own cost.
fn replay_along<D: PersistentQueryDispatcher<ContactManifoldData, ContactData>>(
    dispatcher: &D,
    t: &Trajectory,
    base: &dyn Shape,
    dropped: &dyn Shape,
    rounds: usize,
) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; t.steps.len()];
    for _ in 0..rounds.max(1) {
        for (b, ms) in best
            .iter_mut()
            .zip(replay_once(dispatcher, t, base, dropped))
        {
            *b = b.min(ms);
        }
    }
    best
}

/// One replay of `t` (see [`replay_along`]): rapier's calls of each step
/// made again, in order, with one manifold list and workspace carried from
/// step to step as rapier carries them (both dropped at a step without
/// calls, where rapier drops the pair). A step without calls takes 0 ms.
fn replay_once<D: PersistentQueryDispatcher<ContactManifoldData, ContactData>>(
    dispatcher: &D,
    t: &Trajectory,
    base: &dyn Shape,
    dropped: &dyn Shape,
) -> Vec<f64> {
    let mut manifolds = Vec::new();
    let mut workspace = None;
    t.steps
        .iter()
        .map(|calls| {
            if calls.is_empty() {
                manifolds.clear();
                workspace = None;
                return 0.0;
            }
            let t0 = Instant::now();
            for c in calls {
                let (g1, g2) = if c.base_first {
                    (base, dropped)
                } else {
                    (dropped, base)
                };
                // The run made these calls with this dispatcher's kind:
                // none is unsupported, and an error would only end the
                // call early.
                let _ = dispatcher.contact_manifolds(
                    &c.pos12,
                    g1,
                    g2,
                    c.prediction,
                    &mut manifolds,
                    &mut workspace,
                );
            }
            t0.elapsed().as_secs_f64() * 1e3
        })
        .collect()
}

/// What one run measured.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct RunReport {
    /// The run's name (see [`RunSpec::name`]).
    pub shape: String,
    /// `patches`, `pairs`, or `parry` for parry's own `TriMesh`.
    pub contact_mode: String,
    /// Seconds to build both shapes.
    pub build_seconds: f64,
    /// Narrow-phase (contact manifold) time over the steps in contact.
    pub narrow_phase_ms: TimeStats,
    /// Whole step time over the steps in contact, as the narrow phase's (a
    /// body that rolls off its base would otherwise report its free fall).
    pub step_ms: TimeStats,
    /// Steps with at least one contact point.
    pub steps_in_contact: usize,
    /// Most triangle pairs in contact (within the prediction distance) in
    /// one step.
    pub max_contact_pairs: usize,
    /// Most manifolds with points handed to rapier in one step (one per
    /// triangle pair for parry and the pairs mode, one per patch).
    pub max_manifolds: usize,
    /// Time per step to find every intersecting triangle pair (two-tree
    /// traversal and exact triangle-triangle test, no contacts), over the
    /// steps in contact: the RACBVH and HCCMesh papers' collision figure.
    pub interference_ms: TimeStats,
    /// Most intersecting triangle pairs in one step.
    pub max_interference_pairs: u64,
    /// The largest penetration depth of any contact point during the run.
    pub max_penetration: f32,
    /// The largest angle, in degrees, between a manifold's normal out of
    /// the base and the base's outward surface normal nearest it around
    /// the manifold's triangle (its own and those of the triangles sharing
    /// a corner with it; outward for a closed base, toward the dropped
    /// body's centre for an open one). Near 0 on faces; at a convex edge
    /// or corner up to half the bend between the faces there, where the
    /// normal leans between them; past 90 only for a normal pointing into
    /// the base's surface.
    pub max_normal_angle_deg: f32,
    /// Peak resident memory of the process during this run (building the
    /// shapes and simulating), in bytes, if the platform tells.
    pub peak_rss_bytes: Option<u64>,
    /// Most contact points in one step.
    pub max_contact_points: usize,
    /// Bytes per triangle of the two shapes together.
    pub bytes_per_triangle: f64,
    /// Bytes of the dropped shape and of the base shape.
    pub bytes: [usize; 2],
    /// Final translation of the dropped body.
    pub final_translation: [f32; 3],
    /// Final rotation of the dropped body (quaternion x, y, z, w).
    pub final_rotation: [f32; 4],
    /// Final linear speed of the dropped body.
    pub final_speed: f32,
    /// Where the dropped body ended: `resting` (slower than 5 % of its size
    /// per second and its centre of mass above the base's bottom),
    /// `moving`, `fell off the base` (centre of mass below the base's bottom
    /// and outside its footprint) or `tunnelled through the base` (below
    /// the bottom, inside the footprint).
    pub final_state: String,
    /// The contacts' energy audit: the largest rise of the dropped body's
    /// mechanical energy (kinetic plus gravitational) between its first
    /// and last contact above the lowest it had been since the first (a
    /// body that fell off is not audited in free flight), as a fraction of its
    /// weight times its size (`m·g·size`, the energy of dropping it by its
    /// own size). Contacts without restitution only take energy out, so a
    /// rise is energy the contacts put in: pushing out of deep
    /// penetration, jitter, creeping up. About 0 for a faithful run.
    pub energy_gain: f32,
    /// The decode caches of the dropped and the base shape at the end of
    /// the run (codecs that decode on demand: racbvh, hcc-ooc out of core).
    pub caches: Option<[CacheStats; 2]>,
    /// Whether parry's fallback `Bvh` was built for a cbvh shape.
    pub fallback_bvh_built: bool,
    /// The run whose trajectory the narrow phase was timed along again
    /// after the run ([`Replay`]; `None` without a replay).
    pub replay_along: Option<String>,
    /// The narrow phase timed along that trajectory, over its steps in
    /// contact: the same contact work for every shape timed along it.
    pub replay_narrow_phase_ms: Option<TimeStats>,
    /// Narrow-phase milliseconds of every step of the replay (empty
    /// without one).
    pub replay_narrow_phase_ms_per_step: Vec<f64>,
    /// This run's own trajectory, for other runs to be timed along.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub trajectory: Trajectory,
    /// Narrow-phase milliseconds of every step.
    pub narrow_phase_ms_per_step: Vec<f64>,
    /// Triangle pairs in contact in every step.
    pub contact_pairs_per_step: Vec<usize>,
    /// Manifolds with points in every step.
    pub manifolds_per_step: Vec<usize>,
    /// Interference milliseconds of every step.
    pub interference_ms_per_step: Vec<f64>,
    /// Intersecting triangle pairs of every step.
    pub interference_pairs_per_step: Vec<u64>,
    /// Contact points of every step.
    pub contact_points_per_step: Vec<usize>,
    /// Height (y translation) of the dropped body after every step.
    pub height_per_step: Vec<f32>,
    /// Mechanical energy of the dropped body after every step, in joules
    /// (kinetic plus gravitational relative to the base's bottom; see
    /// [`RunReport::energy_gain`]).
    pub energy_per_step: Vec<f32>,
}

/// The largest rise of `energy` from the first to the last step with
/// contact points, over the lowest value since the first (see [`RunReport::energy_gain`];
/// not yet divided by `m·g·size`).
pub fn energy_rise(energy: &[f32], points_per_step: &[usize]) -> f32 {
    let Some(first) = points_per_step.iter().position(|p| *p > 0) else {
        return 0.0;
    };
    let last = points_per_step
        .iter()
        .rposition(|p| *p > 0)
        .unwrap_or(first);
    let mut low = f32::INFINITY;
    let mut rise = 0.0f32;
    for e in &energy[first..=last] {
        low = low.min(*e);
        rise = rise.max(e - low);
    }
    rise
}

/// What can go wrong running a drop test: building its shapes.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// parry could not build a `TriMesh` (or set its flags).
    #[error("parry TriMesh: {0}")]
    Parry(String),
    /// cbvh could not build a shape.
    #[error(transparent)]
    Cbvh(#[from] crate::parry::ShapeBuildError),
    /// The decode cache could not be limited.
    #[error(transparent)]
    Codec(#[from] crate::codec::CodecError),
    /// A small-cache run of a codec without a cache.
    #[error("{0}: the codec has no cache to limit")]
    NoCache(String),
    /// The dropped mesh's codec file could not be opened again.
    #[error("the dropped mesh's file: {0}")]
    File(String),
}

/// Both meshes' shapes of a run.
enum Shapes {
    Parry(SharedShape, SharedShape, [usize; 2]),
    Cbvh(CbvhShape, CbvhShape),
}

impl Shapes {
    /// The shapes as rapier takes them (dropped, base), their bytes, and
    /// the cbvh shapes themselves for their caches.
    fn shared(&self) -> (SharedShape, SharedShape, [usize; 2]) {
        match self {
            Shapes::Parry(a, b, bytes) => (a.clone(), b.clone(), *bytes),
            Shapes::Cbvh(a, b) => (
                SharedShape::new(a.clone()),
                SharedShape::new(b.clone()),
                [a.bytes_total(), b.bytes_total()],
            ),
        }
    }

    /// The base's triangle count.
    fn base_count(&self) -> usize {
        match self {
            Shapes::Cbvh(_, b) => b.triangle_count(),
            Shapes::Parry(_, b, _) => b
                .as_shape::<parry3d::shape::TriMesh>()
                .map_or(0, |t| t.indices().len()),
        }
    }

    /// The base's triangle `id` as the shape stores it.
    fn base_triangle(&self, id: u32) -> Option<[Vector; 3]> {
        match self {
            Shapes::Cbvh(_, b) => {
                let t = b.parry_triangle(id);
                Some([t.a, t.b, t.c])
            }
            Shapes::Parry(_, b, _) => {
                let tm = b.as_shape::<parry3d::shape::TriMesh>()?;
                let t = tm.triangle(id);
                Some([t.a, t.b, t.c])
            }
        }
    }

    /// The papers' interference figure: intersecting triangle pairs at the
    /// relative pose `pos12`.
    fn interference(&self, pos12: &PPose) -> u64 {
        match self {
            Shapes::Cbvh(a, b) => interference(pos12, a, b),
            Shapes::Parry(a, b, _) => {
                let (Some(ta), Some(tb)) = (
                    a.as_shape::<parry3d::shape::TriMesh>(),
                    b.as_shape::<parry3d::shape::TriMesh>(),
                ) else {
                    unreachable!("parry runs use TriMesh shapes")
                };
                trimesh_interference(pos12, ta, tb)
            }
        }
    }
}

fn make_shapes(kind: ShapeKind, scene: &DropScene) -> Result<Shapes, SimError> {
    let (codec, small_cache) = match kind {
        ShapeKind::Parry | ShapeKind::ParryFixed => {
            let parry = |e: &dyn std::fmt::Debug| SimError::Parry(format!("{e:?}"));
            let mut a = parry_trimesh(&scene.dropped).map_err(|e| parry(&e))?;
            let mut b = parry_trimesh(&scene.base).map_err(|e| parry(&e))?;
            if kind == ShapeKind::ParryFixed {
                for t in [&mut a, &mut b] {
                    t.set_flags(TriMeshFlags::FIX_INTERNAL_EDGES)
                        .map_err(|e| parry(&e))?;
                }
            }
            let bytes = [
                trimesh_bytes_by_part(&a).iter().map(|p| p.1).sum(),
                trimesh_bytes_by_part(&b).iter().map(|p| p.1).sum(),
            ];
            return Ok(Shapes::Parry(
                SharedShape::new(a),
                SharedShape::new(b),
                bytes,
            ));
        }
        ShapeKind::Cbvh(k) => (k, false),
        ShapeKind::CbvhTenthCache(k) => (k, true),
    };
    // Caches start out holding the whole tree.
    let options = scene.codec_options.clone().with_cache_budget(usize::MAX);
    let make = |m: &Mesh| -> Result<CbvhShape, SimError> {
        let shape = CbvhShape::build(m, &scene.build_options, codec, &options)?;
        if !small_cache {
            return Ok(shape);
        }
        // 10 % of the decompressed size: measured by decoding the whole
        // tree once with the unbounded cache, then the same bytes re-opened
        // with a tenth of it.
        let rebudget = |codec: &AnyCodec, budget: &dyn Fn(usize) -> usize| {
            codec
                .with_cache_budget_of(budget)
                .ok_or_else(|| SimError::NoCache(kind.name()))
        };
        let small = rebudget(shape.codec(), &|decoded| decoded / 10)??;
        if !codec.encodes_for_cache_budget() {
            return Ok(CbvhShape::from_codec(small, m));
        }
        // A codec that encodes for its budget (RACBVH: the cluster size) is
        // encoded again for that budget, as a user who knows it would, and
        // then given a tenth of what that encoding decodes to (measured
        // with an unbounded cache again).
        let budget = small.cache_stats().map_or(usize::MAX, |s| s.budget_bytes);
        let options = options.clone().with_cache_budget(budget);
        let shape = CbvhShape::build(m, &scene.build_options, codec, &options)?;
        let whole = rebudget(shape.codec(), &|_| usize::MAX)??;
        Ok(CbvhShape::from_codec(
            rebudget(&whole, &|decoded| decoded / 10)??,
            m,
        ))
    };
    let dropped = match &scene.dropped_file {
        Some(f) if f.kind == codec => {
            // The file's codec as it is: the whole tree cached, or opened
            // with a 1 MiB cache (out of core, nothing decoded yet) and
            // given a tenth of what it decodes to.
            let open = |budget| {
                AnyCodec::open(
                    &f.path,
                    &OpenOptions {
                        verify: false,
                        cache_budget_bytes: budget,
                    },
                )
                .map_err(|e| SimError::File(e.to_string()))
            };
            let c = if small_cache {
                open(1 << 20)?
                    .with_cache_budget_of(&|decoded| decoded / 10)
                    .ok_or_else(|| SimError::NoCache(kind.name()))??
            } else {
                open(usize::MAX)?
            };
            CbvhShape::new(c)
        }
        _ => make(&scene.dropped)?,
    };
    Ok(Shapes::Cbvh(dropped, make(&scene.base)?))
}

/// See [`RunReport::final_state`].
fn final_state(scene: &DropScene, com: Vector, speed: f32) -> String {
    let (Some((blo, bhi)), Some((dlo, dhi))) = (scene.base.bounds(), scene.dropped_bounds()) else {
        return "moving".into();
    };
    let size = (0..3).map(|k| dhi[k] - dlo[k]).fold(0.0f32, f32::max);
    if com.y < blo[1] {
        let inside = (blo[0]..=bhi[0]).contains(&com.x) && (blo[2]..=bhi[2]).contains(&com.z);
        return if inside {
            "tunnelled through the base".into()
        } else {
            "fell off the base".into()
        };
    }
    if speed < 0.05 * size {
        "resting"
    } else {
        "moving"
    }
    .into()
}

/// Runs the drop test with `spec`'s shapes and contact mode.
/// `progress(step, steps)` is called after every step.
pub fn run(
    scene: &DropScene,
    spec: RunSpec,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RunReport, SimError> {
    run_replaying(scene, spec, Replay::Off, REPLAY_ROUNDS, progress)
}

/// [`run`], then the narrow phase timed once more along the trajectory
/// `replay` names, with the run's shapes and a fresh dispatcher of the
/// run's kind (a decode cache as the run left it): each step's best of
/// `rounds` replays (see [`REPLAY_ROUNDS`]).
pub fn run_replaying(
    scene: &DropScene,
    spec: RunSpec,
    replay: Replay<'_>,
    rounds: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RunReport, SimError> {
    let mut run = Run::new(scene, spec)?;
    let audit = NormalAudit::new(scene, &run.shapes);
    let mut samples = Samples::with_capacity(scene.steps);
    for step in 0..scene.steps {
        samples.step(&mut run, &audit);
        progress(step + 1, scene.steps);
    }
    Ok(report(scene, run, samples, replay, rounds))
}

/// A run set up in rapier: the two bodies on their shapes, the timed
/// dispatcher recording every call.
struct Run {
    spec: RunSpec,
    shapes: Shapes,
    s_drop: SharedShape,
    s_base: SharedShape,
    bytes: [usize; 2],
    build_seconds: f64,
    rss_reset: bool,
    world: PhysicsWorld,
    drop_body: RigidBodyHandle,
    base_body: RigidBodyHandle,
    base_collider: ColliderHandle,
    /// Nanoseconds spent in the dispatcher so far.
    counter: std::sync::Arc<std::sync::atomic::AtomicU64>,
    /// cbvh's contact counters (triangle-pair contacts of the step).
    counters: std::sync::Arc<ContactCounters>,
    /// The dispatcher's calls since the last step.
    call_log: super::timed::CallLog,
    base_address: usize,
    /// The base's lowest point (the energy audit's zero of potential).
    floor: f32,
}

impl Run {
    fn new(scene: &DropScene, spec: RunSpec) -> Result<Self, SimError> {
        let kind = spec.kind;
        let rss_reset = reset_peak_rss();
        let t0 = Instant::now();
        let shapes = make_shapes(kind, scene)?;
        let build_seconds = t0.elapsed().as_secs_f64();
        let (s_drop, s_base, bytes) = shapes.shared();
        let counters = ContactCounters::shared();
        let timed = match kind {
            ShapeKind::Parry | ShapeKind::ParryFixed => None,
            _ => Some(
                Timed::new(
                    Dispatcher::new(spec.mode)
                        .with_counters(counters.clone())
                        .then_default(),
                )
                .recording(),
            ),
        };
        let parry_timed = Timed::new(DefaultQueryDispatcher).recording();
        let (counter, call_log) = match &timed {
            Some(t) => (t.counter(), t.calls()),
            None => (parry_timed.counter(), parry_timed.calls()),
        };
        let call_log = call_log.expect("both dispatchers record");
        let base_address = shape_address(&*s_base.0);
        let mut world = PhysicsWorld {
            gravity: Vector::new(0.0, -9.81 * scene.length_unit, 0.0),
            ..Default::default()
        };
        world.integration_parameters.dt = scene.dt;
        world.integration_parameters.length_unit = scene.length_unit;
        // Contact recycling skips the narrow phase while a pair's relative
        // pose drifts less than a threshold, reusing old contacts: that
        // would time nothing. The drop test measures collision detection,
        // so every step recomputes contacts (as in the RACBVH paper's
        // benchmark).
        world.integration_parameters.contact_recycling = scene.contact_recycling;
        world.narrow_phase = match timed {
            Some(t) => NarrowPhase::with_query_dispatcher(t),
            None => NarrowPhase::with_query_dispatcher(parry_timed),
        };
        let base_body = world.bodies.insert(RigidBodyBuilder::fixed());
        let drop_body: RigidBodyHandle = world
            .bodies
            .insert(RigidBodyBuilder::dynamic().can_sleep(false));
        let base_collider: ColliderHandle = world.colliders.insert_with_parent(
            ColliderBuilder::new(s_base.clone()).friction(0.6),
            base_body,
            &mut world.bodies,
        );
        world.colliders.insert_with_parent(
            ColliderBuilder::new(s_drop.clone())
                .density(1.0)
                .friction(0.6),
            drop_body,
            &mut world.bodies,
        );
        Ok(Self {
            spec,
            shapes,
            s_drop,
            s_base,
            bytes,
            build_seconds,
            rss_reset,
            world,
            drop_body,
            base_body,
            base_collider,
            counter,
            counters,
            call_log,
            base_address,
            floor: scene.base.bounds().map_or(0.0, |(lo, _)| lo[1]),
        })
    }
}

/// The normal audit: the largest angle between an emitted normal and the
/// base's outward surface normal around the contact.
struct NormalAudit {
    /// Whether the base is closed, and its outward side (from the mesh, as
    /// every representation has the same surface).
    base_edges: EdgeFlags,
    around: Neighbourhoods,
}

impl NormalAudit {
    fn new(scene: &DropScene, shapes: &Shapes) -> Self {
        let base_edges = EdgeFlags::compute(scene.base.triangles.len(), |t| {
            crate::geom::triangle_from_arrays(scene.base.triangle_vertices(t as usize))
        });
        let around = Neighbourhoods::new(shapes.base_count(), &|id| shapes.base_triangle(id));
        Self { base_edges, around }
    }

    /// The angle in degrees between `n` (out of the base, in its frame) and
    /// the base's outward surface normal nearest it among the triangles
    /// around triangle `id` (at an edge or a corner the surface has every
    /// normal between theirs); `None` when there is none to compare.
    fn angle(&self, shapes: &Shapes, n: Vector, id: u32, drop_centre: Vector) -> Option<f32> {
        let outward = |t: [Vector; 3]| {
            let face = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            let sign = if self.base_edges.is_closed() {
                self.base_edges.outward()
            } else if face.dot(drop_centre - t[0]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            face * sign
        };
        let best = self
            .around
            .of(id)
            .filter_map(|k| shapes.base_triangle(k).map(outward))
            .filter(|f| *f != Vector::ZERO)
            .map(|f| n.dot(f).clamp(-1.0, 1.0))
            .fold(None, |a: Option<f32>, c| Some(a.map_or(c, |a| a.max(c))));
        best.filter(|_| n != Vector::ZERO)
            .map(|cos| cos.acos().to_degrees())
    }
}

/// What a run measures, step by step.
struct Samples {
    narrow: Vec<f64>,
    step_ms: Vec<f64>,
    pairs: Vec<usize>,
    manifolds: Vec<usize>,
    points: Vec<usize>,
    heights: Vec<f32>,
    inter_ms: Vec<f64>,
    inter_pairs: Vec<u64>,
    energy: Vec<f32>,
    calls: Vec<Vec<Call>>,
    max_penetration: f32,
    max_normal_angle: f32,
}

impl Samples {
    fn with_capacity(steps: usize) -> Self {
        Self {
            narrow: Vec::with_capacity(steps),
            step_ms: Vec::with_capacity(steps),
            pairs: Vec::with_capacity(steps),
            manifolds: Vec::with_capacity(steps),
            points: Vec::with_capacity(steps),
            heights: Vec::with_capacity(steps),
            inter_ms: Vec::with_capacity(steps),
            inter_pairs: Vec::with_capacity(steps),
            energy: Vec::with_capacity(steps),
            calls: Vec::with_capacity(steps),
            max_penetration: 0.0,
            max_normal_angle: 0.0,
        }
    }

    /// Steps the world once and records the step.
    fn step(&mut self, run: &mut Run, audit: &NormalAudit) {
        let before = run.counter.load(Ordering::Relaxed);
        run.counters.take();
        let t = Instant::now();
        run.world.step();
        self.step_ms.push(t.elapsed().as_secs_f64() * 1e3);
        self.narrow
            .push((run.counter.load(Ordering::Relaxed) - before) as f64 / 1e6);
        let calls = std::mem::take(&mut *run.call_log.lock().unwrap_or_else(|e| e.into_inner()));
        self.calls.push(
            calls
                .into_iter()
                .map(|c| Call {
                    pos12: c.pos12,
                    prediction: c.prediction,
                    base_first: c.first == run.base_address,
                })
                .collect(),
        );
        let [_, tri_contacts, _] = run.counters.take();
        let (mut manifolds, mut points) = (0, 0);
        let drop_centre = run.world.bodies[run.drop_body].center_of_mass();
        for pair in run.world.narrow_phase.contact_pairs() {
            let base_first = pair.collider1 == run.base_collider;
            for m in pair.manifolds() {
                if !m.points.is_empty() {
                    manifolds += 1;
                    points += m.points.len();
                    // The normal out of the base, in the base's frame (the
                    // base body sits at the origin).
                    let (n, id) = if base_first {
                        (m.local_n1, m.subshape1)
                    } else {
                        (m.local_n2, m.subshape2)
                    };
                    if let Some(angle) = audit.angle(&run.shapes, n, id, drop_centre) {
                        self.max_normal_angle = self.max_normal_angle.max(angle);
                    }
                }
                for p in &m.points {
                    self.max_penetration = self.max_penetration.max(-p.dist);
                }
            }
        }
        let contact_pairs = match run.spec.mode {
            ContactMode::Patches(_) if !run.spec.kind.is_parry() => tri_contacts as usize,
            _ => manifolds,
        };
        // The papers' interference figure at this step's pose.
        let world = &run.world;
        let pos12 = world.bodies[run.drop_body]
            .position()
            .inv_mul(world.bodies[run.base_body].position());
        let ti = Instant::now();
        let n_inter = run.shapes.interference(&pos12);
        self.inter_ms.push(ti.elapsed().as_secs_f64() * 1e3);
        self.inter_pairs.push(n_inter);
        let body = &world.bodies[run.drop_body];
        self.heights.push(body.translation().y);
        // rapier's leap-frog form: the potential at the half step, in step
        // with the kinetic energy of the velocities just integrated.
        let dt = world.integration_parameters.dt;
        self.energy.push(
            body.kinetic_energy()
                + body.gravitational_potential_energy(dt, world.gravity)
                + body.mass() * world.gravity.y * run.floor,
        );
        self.pairs.push(contact_pairs);
        self.manifolds.push(manifolds);
        self.points.push(points);
    }
}

/// The run's report from its samples, after the replay if one is asked.
fn report(scene: &DropScene, run: Run, s: Samples, replay: Replay<'_>, rounds: usize) -> RunReport {
    let (spec, kind) = (run.spec, run.spec.kind);
    let in_contact = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .zip(&s.points)
            .filter(|(_, p)| **p > 0)
            .map(|(t, _)| *t)
            .collect()
    };
    let narrow_in_contact = in_contact(&s.narrow);
    let trajectory = Trajectory {
        from: spec.name(),
        steps: s.calls,
        in_contact: s.points.iter().map(|&p| p > 0).collect(),
    };
    let along = match replay {
        Replay::Off => None,
        Replay::Own => Some(&trajectory),
        Replay::Along(t) => Some(t),
    };
    let replay_ms = along.map(|t| {
        let ms = match kind {
            ShapeKind::Parry | ShapeKind::ParryFixed => replay_along(
                &DefaultQueryDispatcher,
                t,
                &*run.s_base,
                &*run.s_drop,
                rounds,
            ),
            _ => replay_along(
                &Dispatcher::new(spec.mode).then_default(),
                t,
                &*run.s_base,
                &*run.s_drop,
                rounds,
            ),
        };
        let stats = TimeStats::of(
            &ms.iter()
                .zip(&t.in_contact)
                .filter(|(_, c)| **c)
                .map(|(m, _)| *m)
                .collect::<Vec<_>>(),
        );
        (t.from.clone(), stats, ms)
    });
    let world = &run.world;
    let body = &world.bodies[run.drop_body];
    let tr = body.translation();
    let rot = body.rotation();
    let tris = scene.dropped_triangles() + scene.base.triangles.len();
    let size = scene.dropped_bounds().map_or(0.0, |(lo, hi)| {
        (0..3).map(|k| hi[k] - lo[k]).fold(0.0f32, f32::max)
    });
    let drop_scale = body.mass() * world.gravity.length() * size;
    let cbvh = match &run.shapes {
        Shapes::Cbvh(a, b) => Some((a, b)),
        Shapes::Parry(..) => None,
    };
    let bytes = run.bytes;
    RunReport {
        shape: spec.name(),
        contact_mode: if kind.is_parry() {
            "parry".into()
        } else {
            spec.mode.name().into()
        },
        build_seconds: run.build_seconds,
        narrow_phase_ms: TimeStats::of(&narrow_in_contact),
        step_ms: TimeStats::of(&in_contact(&s.step_ms)),
        steps_in_contact: narrow_in_contact.len(),
        max_contact_pairs: s.pairs.iter().copied().max().unwrap_or(0),
        max_manifolds: s.manifolds.iter().copied().max().unwrap_or(0),
        max_contact_points: s.points.iter().copied().max().unwrap_or(0),
        interference_ms: TimeStats::of(&in_contact(&s.inter_ms)),
        max_interference_pairs: s.inter_pairs.iter().copied().max().unwrap_or(0),
        max_penetration: s.max_penetration,
        max_normal_angle_deg: s.max_normal_angle,
        peak_rss_bytes: if run.rss_reset {
            peak_rss_bytes()
        } else {
            None
        },
        bytes_per_triangle: (bytes[0] + bytes[1]) as f64 / tris.max(1) as f64,
        bytes,
        final_translation: [tr.x, tr.y, tr.z],
        final_rotation: [rot.x, rot.y, rot.z, rot.w],
        final_speed: body.linvel().length(),
        final_state: final_state(scene, body.center_of_mass(), body.linvel().length()),
        energy_gain: energy_rise(&s.energy, &s.points) / drop_scale.max(f32::MIN_POSITIVE),
        caches: cbvh.and_then(|(a, b)| Some([a.codec().cache_stats()?, b.codec().cache_stats()?])),
        fallback_bvh_built: cbvh
            .is_some_and(|(a, b)| a.fallback_bvh_built() || b.fallback_bvh_built()),
        replay_along: replay_ms.as_ref().map(|r| r.0.clone()),
        replay_narrow_phase_ms: replay_ms.as_ref().map(|r| r.1),
        replay_narrow_phase_ms_per_step: replay_ms.map(|r| r.2).unwrap_or_default(),
        trajectory,
        narrow_phase_ms_per_step: s.narrow,
        contact_pairs_per_step: s.pairs,
        manifolds_per_step: s.manifolds,
        interference_ms_per_step: s.inter_ms,
        interference_pairs_per_step: s.inter_pairs,
        contact_points_per_step: s.points,
        height_per_step: s.heights,
        energy_per_step: s.energy,
    }
}

/// The triangles around each triangle of a mesh (those sharing a corner
/// with it, itself included), for the normal audit: corners matched by
/// their exact coordinates, in compressed rows (about 30 bytes a triangle).
struct Neighbourhoods {
    /// Each triangle's three corner indices.
    corners: Vec<[u32; 3]>,
    /// Row starts of `tris` by corner index.
    start: Vec<u32>,
    /// The triangles at each corner, row by row.
    tris: Vec<u32>,
}

impl Neighbourhoods {
    fn new(count: usize, triangle: &impl Fn(u32) -> Option<[Vector; 3]>) -> Self {
        let key = |v: Vector| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        let mut index = std::collections::HashMap::<[u32; 3], u32>::new();
        let corners: Vec<[u32; 3]> = (0..count as u32)
            .map(|i| {
                let t = triangle(i).unwrap_or([Vector::ZERO; 3]);
                t.map(|v| {
                    let next = index.len() as u32;
                    *index.entry(key(v)).or_insert(next)
                })
            })
            .collect();
        let mut start = vec![0u32; index.len() + 1];
        for c in corners.iter().flatten() {
            start[*c as usize + 1] += 1;
        }
        for k in 1..start.len() {
            start[k] += start[k - 1];
        }
        let mut fill = start.clone();
        let mut tris = vec![0u32; start[index.len()] as usize];
        for (i, cs) in corners.iter().enumerate() {
            for c in cs {
                tris[fill[*c as usize] as usize] = i as u32;
                fill[*c as usize] += 1;
            }
        }
        Self {
            corners,
            start,
            tris,
        }
    }

    /// The triangles around triangle `id` (repeats included), or just `id`
    /// when it is out of range.
    fn of(&self, id: u32) -> impl Iterator<Item = u32> + '_ {
        let cs = self.corners.get(id as usize).copied();
        let rows = cs.into_iter().flatten().flat_map(move |c| {
            let (a, b) = (self.start[c as usize], self.start[c as usize + 1]);
            self.tris[a as usize..b as usize].iter().copied()
        });
        std::iter::once(id).chain(rows)
    }
}

#[cfg(test)]
mod tests {
    use super::energy_rise;

    #[test]
    fn energy_rise_counts_only_rises_between_first_and_last_contact() {
        // Free fall before contact (10 -> 9.5) and after it (a rise to 30 in
        // flight) is not audited; inside, 9 -> 9.5 is a rise of 0.5, and
        // the later 8 -> 8.2 is smaller.
        let e = [10.0, 9.5, 9.0, 9.5, 8.0, 8.2, 30.0];
        let pts = [0, 0, 3, 2, 4, 1, 0];
        assert!((energy_rise(&e, &pts) - 0.5).abs() < 1e-6);
        // Falling energy only: nothing put in.
        assert_eq!(energy_rise(&[5.0, 4.0, 3.0], &[1, 1, 1]), 0.0);
        // No contact at all.
        assert_eq!(energy_rise(&[1.0, 2.0], &[0, 0]), 0.0);
    }
}
