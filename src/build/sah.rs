//! Binned SAH construction, parallel with rayon, without recursion.
//!
//! # Slots
//!
//! Each triangle becomes a 32-byte reference (its box and id). A subtree over
//! `n` references owns exactly `2n - 1` node slots laid out in pre-order: the
//! subtree root, then the left subtree's `2n_l - 1` slots, then the right
//! subtree's. A `Job` is a subtree still to build: its references, its slots
//! and their global offsets. Splitting a job's root fills the root's slot and
//! cuts both slices in two with `split_at_mut`, which gives two independent
//! jobs: no locks and no unsafe code. A leaf over `k > 1` triangles leaves
//! `2k - 2` slots unused; the layout pass drops them.
//!
//! # Scheduling: no recursion over the tree
//!
//! The stack a build uses does not grow with the input. (It used to: the
//! builder recursed once per level under `rayon::join` with its bin arrays
//! on every frame, about 52 KB a level, and overflowed rayon's worker stacks
//! on flat input, where the tree got deep.)
//!
//! - A job of at least [`PARALLEL_THRESHOLD`] references is a task of a
//!   `rayon::scope` that loops: split the root, spawn the right child as a
//!   new task, go on with the left. A spawned task starts from a worker's
//!   scheduling loop, not on top of the task that spawned it, so tasks do not
//!   pile up on one stack as nested `join`s do.
//! - A job under the threshold is built whole by the thread that holds it,
//!   with a loop over a `Vec` of pending jobs (at most one per level).
//! - Bin arrays and sweep buffers live in one heap `Scratch` per task,
//!   reused for every node the task splits.
//!
//! A mesh under the threshold is built on the calling thread. A split
//! depends only on its node's references and each subtree writes only its
//! own slots, so the tree is the same whatever the number of threads and the
//! order in which tasks run.
//!
//! # Splits
//!
//! A node splits at the best binned-SAH plane over `bins` centroid bins on
//! each axis (at most 8 bins below 64 references, 32 below 1024); of
//! candidates of exactly equal cost, the most even one wins (quantized
//! coordinates make such ties). Where the SAH cannot separate a node, the
//! split falls back to a median, which always makes progress:
//!
//! - every centroid is the same point (no plane separates them): the object
//!   median, where every key ties, so the split is by index, half and half;
//! - no candidate costs less than keeping the node whole (`area × m` over
//!   `m` references, with a relative margin of [`MIN_SAH_GAIN`] for
//!   rounding): every candidate's children are as large as the node, or
//!   every box has zero area, as in a collinear mesh or a scan translated
//!   so far that `f32` rounding flattens its boxes. All costs are then
//!   equal (0 for zero areas), and taking the first candidate peeled one bin
//!   off per level. Such a node is split at the object median along its
//!   longest centroid axis. No split costs more than `area × m`, so this is
//!   at most [`MIN_SAH_GAIN`] worse than the SAH's pick at that node. (Two
//!   references have one partition whatever the rule; they keep the SAH's.)
//!
//! For any input the height is at most `H = 2⌊log2 n⌋ + 16`, `n` the mesh's
//! triangle count: a node at depth `d` (the root is at depth 1) over `m`
//! references uses the SAH only if `d + 1 + ⌈log2 m⌉ ≤ H`, and the median
//! otherwise. Every node then has `d + ⌈log2 m⌉ ≤ H` (an SAH child is one
//! level deeper with fewer references; a median child is one level deeper
//! with `⌈log2 m⌉ - 1`), so no leaf is deeper than `H`. The budget is for
//! pathological input, where every SAH split is rightly lopsided (nested
//! triangles, exponentially clustered centroids), and replaces a fixed SAH
//! depth of 64, which allowed heights of `64 + log2 n`.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3A;
use rayon::prelude::*;

use super::{BuildOptions, CanonicalNode, LEAF_FLAG};
use crate::geom::Aabb;
use crate::mesh::Mesh;

/// Jobs of at least this many references are split as rayon tasks; smaller
/// ones are built whole by one thread.
const PARALLEL_THRESHOLD: usize = 4096;
/// Nodes with more references than this bin in parallel chunks.
const PARALLEL_BINNING: usize = 1 << 16;
/// The height budget is `2⌊log2 n⌋` plus this.
const HEIGHT_SLACK: usize = 16;
/// How much cheaper than keeping the node whole (relatively) the best SAH
/// split must be to be taken; below that the node is split at the median.
const MIN_SAH_GAIN: f32 = 1e-5;

/// A tree in build order (pre-order with unused slots), before layout.
pub(super) struct BuiltTree {
    pub nodes: Vec<CanonicalNode>,
    pub leaf_triangles: Vec<u32>,
}

#[derive(Clone, Copy)]
#[repr(C)]
struct Ref {
    min: [f32; 3],
    id: u32,
    max: [f32; 3],
    _pad: u32,
}

impl Ref {
    #[inline]
    fn aabb(&self) -> Aabb {
        Aabb::from_arrays(self.min, self.max)
    }
    #[inline]
    fn centroid(&self) -> Vec3A {
        (Vec3A::from(self.min) + Vec3A::from(self.max)) * 0.5
    }
}

struct Ctx<'a> {
    max_leaf: usize,
    bins: usize,
    /// The deepest a leaf may be (the root is at depth 1).
    height_budget: usize,
    done: AtomicU64,
    total: u64,
    step: u64,
    progress: &'a (dyn Fn(u64, u64) + Sync),
}

impl Ctx<'_> {
    fn report(&self, k: u64) {
        let before = self.done.fetch_add(k, Ordering::Relaxed);
        if (before + k) / self.step != before / self.step {
            (self.progress)(before + k, self.total);
        }
    }
}

/// A subtree still to build: its references and its `2 refs.len() - 1` node
/// slots, with the global indices of `nodes[0]` and `refs[0]`.
struct Job<'a> {
    refs: &'a mut [Ref],
    nodes: &'a mut [CanonicalNode],
    node_base: u32,
    ref_base: u32,
    /// Depth of the subtree's root (the tree's root is at depth 1).
    depth: usize,
}

/// What became of a job's root.
enum Step<'a> {
    /// A leaf over this many references.
    Leaf(usize),
    /// An inner node with these two subtrees to build.
    Inner(Job<'a>, Job<'a>),
}

const UNUSED: CanonicalNode = CanonicalNode {
    min: [0.0; 3],
    max: [0.0; 3],
    a: u32::MAX,
    b: u32::MAX,
};

pub(super) fn build_tree(
    mesh: &Mesh,
    options: &BuildOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> BuiltTree {
    let n = mesh.triangles.len();
    if n == 0 {
        return BuiltTree {
            nodes: vec![CanonicalNode {
                min: [f32::INFINITY; 3],
                max: [f32::NEG_INFINITY; 3],
                a: 0,
                b: LEAF_FLAG,
            }],
            leaf_triangles: Vec::new(),
        };
    }
    let mut refs: Vec<Ref> = (0..n as u32)
        .into_par_iter()
        .map(|id| {
            let [a, b, c] = mesh.triangle_vertices(id as usize);
            let mut min = a;
            let mut max = a;
            for p in [b, c] {
                for k in 0..3 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
            Ref {
                min,
                id,
                max,
                _pad: 0,
            }
        })
        .collect();
    let mut nodes = vec![UNUSED; 2 * n - 1];
    let ctx = Ctx {
        max_leaf: options.max_leaf_triangles,
        bins: options.bins,
        height_budget: 2 * n.ilog2() as usize + HEIGHT_SLACK,
        done: AtomicU64::new(0),
        total: n as u64,
        step: (n as u64 / 100).max(1),
        progress,
    };
    let root = Job {
        refs: &mut refs,
        nodes: &mut nodes,
        node_base: 0,
        ref_base: 0,
        depth: 1,
    };
    if n < PARALLEL_THRESHOLD {
        build_serial(&ctx, root, &mut Scratch::new());
    } else {
        rayon::scope(|s| build_parallel(s, &ctx, root));
    }
    let leaf_triangles = refs.par_iter().map(|r| r.id).collect();
    BuiltTree {
        nodes,
        leaf_triangles,
    }
}

/// A scope task: splits `job` down its left spine while it is large,
/// spawning each right subtree as a new task, then builds the rest itself.
fn build_parallel<'s>(scope: &rayon::Scope<'s>, ctx: &'s Ctx<'s>, mut job: Job<'s>) {
    let mut scratch = Scratch::new();
    while job.refs.len() >= PARALLEL_THRESHOLD {
        match split(ctx, job, &mut scratch) {
            Step::Leaf(k) => {
                ctx.report(k as u64);
                return;
            }
            Step::Inner(left, right) => {
                scope.spawn(move |s| build_parallel(s, ctx, right));
                job = left;
            }
        }
    }
    build_serial(ctx, job, &mut scratch);
}

/// Builds the whole subtree of `job` on this thread, depth first, with the
/// pending right subtrees in a `Vec` (at most one per level).
fn build_serial(ctx: &Ctx, job: Job, scratch: &mut Scratch) {
    let mut leaves = 0;
    let mut pending = Vec::with_capacity(64);
    pending.push(job);
    while let Some(job) = pending.pop() {
        match split(ctx, job, scratch) {
            Step::Leaf(k) => leaves += k,
            Step::Inner(left, right) => {
                pending.push(right);
                pending.push(left);
            }
        }
    }
    ctx.report(leaves as u64);
}

fn bounds_of(refs: &[Ref]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut c = Aabb::EMPTY;
    for r in refs {
        b = b.union(&r.aabb());
        c.grow(r.centroid());
    }
    (b, c)
}

/// `⌈log2 n⌉` for `n ≥ 1`.
#[inline]
fn ceil_log2(n: usize) -> usize {
    n.next_power_of_two().ilog2() as usize
}

/// Makes the root of `job` a leaf or splits it, filling its slot.
fn split<'a>(ctx: &Ctx, job: Job<'a>, scratch: &mut Scratch) -> Step<'a> {
    let Job {
        refs,
        nodes,
        node_base,
        ref_base,
        depth,
    } = job;
    let n = refs.len();
    debug_assert_eq!(nodes.len(), 2 * n - 1);
    let (bounds, cbounds) = bounds_of(refs);
    if n <= ctx.max_leaf {
        nodes[0] = CanonicalNode {
            min: bounds.min.into(),
            max: bounds.max.into(),
            a: ref_base,
            b: LEAF_FLAG | n as u32,
        };
        return Step::Leaf(n);
    }
    let sah = depth + 1 + ceil_log2(n) <= ctx.height_budget;
    let mid = sah
        .then(|| sah_split(refs, &bounds, &cbounds, ctx.bins, scratch))
        .flatten()
        .unwrap_or_else(|| median_split(refs, &cbounds));
    debug_assert!(mid > 0 && mid < n);
    let (left_refs, right_refs) = refs.split_at_mut(mid);
    let (head, rest) = nodes.split_at_mut(1);
    let (left_nodes, right_nodes) = rest.split_at_mut(2 * mid - 1);
    let left = node_base + 1;
    let right = node_base + 2 * mid as u32;
    head[0] = CanonicalNode {
        min: bounds.min.into(),
        max: bounds.max.into(),
        a: left,
        b: right,
    };
    Step::Inner(
        Job {
            refs: left_refs,
            nodes: left_nodes,
            node_base: left,
            ref_base,
            depth: depth + 1,
        },
        Job {
            refs: right_refs,
            nodes: right_nodes,
            node_base: right,
            ref_base: ref_base + mid as u32,
            depth: depth + 1,
        },
    )
}

/// Object-median split on the longest centroid axis. Over identical
/// centroids every key ties and the split is by index, half and half.
fn median_split(refs: &mut [Ref], cbounds: &Aabb) -> usize {
    let e = cbounds.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| {
        let ca = a.min[axis] + a.max[axis];
        let cb = b.min[axis] + b.max[axis];
        ca.total_cmp(&cb)
    });
    mid
}

/// Per-axis bin counts and boxes, for at most `N` bins. Small nodes use a
/// small `N`: clearing the bins is a per-node cost, and there are as many
/// small nodes as triangles.
#[derive(Clone)]
struct Bins<const N: usize> {
    counts: [[u32; N]; 3],
    boxes: [[Aabb; N]; 3],
}

impl<const N: usize> Bins<N> {
    fn new() -> Self {
        Self {
            counts: [[0; N]; 3],
            boxes: [[Aabb::EMPTY; N]; 3],
        }
    }

    /// Empties the first `bins` bins of each axis.
    fn clear(&mut self, bins: usize) {
        for axis in 0..3 {
            self.counts[axis][..bins].fill(0);
            self.boxes[axis][..bins].fill(Aabb::EMPTY);
        }
    }

    /// Bins every reference on all three axes in one pass over memory.
    fn fill(&mut self, refs: &[Ref], lo: Vec3A, scale: Vec3A, bins: usize) {
        for r in refs {
            let b = r.aabb();
            let idx = bin_index(r.centroid(), lo, scale, bins);
            for (axis, &i) in idx.iter().enumerate() {
                self.counts[axis][i] += 1;
                self.boxes[axis][i] = self.boxes[axis][i].union(&b);
            }
        }
    }

    fn merge(mut self, o: &Self, bins: usize) -> Self {
        for axis in 0..3 {
            let counts = self.counts[axis].iter_mut().zip(&o.counts[axis]);
            for (a, b) in counts.take(bins) {
                *a += b;
            }
            let boxes = self.boxes[axis].iter_mut().zip(&o.boxes[axis]);
            for (a, b) in boxes.take(bins) {
                *a = a.union(b);
            }
        }
        self
    }
}

/// The most bins [`BuildOptions::bins`] allows.
const MAX_BINS: usize = 255;

/// A task's reusable binning memory, on the heap: about 30 KB that used to
/// sit on every recursion frame.
struct Scratch {
    bins8: Bins<8>,
    bins32: Bins<32>,
    bins255: Bins<MAX_BINS>,
    /// Sweep buffers: half area and count of bins `[i, bins)`.
    right_area: [f32; MAX_BINS],
    right_count: [u32; MAX_BINS],
}

impl Scratch {
    fn new() -> Box<Self> {
        Box::new(Self {
            bins8: Bins::new(),
            bins32: Bins::new(),
            bins255: Bins::new(),
            right_area: [0.0; MAX_BINS],
            right_count: [0; MAX_BINS],
        })
    }
}

/// Bin indices of a centroid on the three axes (0 on a flat axis).
#[inline]
fn bin_index(c: Vec3A, lo: Vec3A, scale: Vec3A, bins: usize) -> [usize; 3] {
    let f = ((c - lo) * scale).to_array();
    [
        (f[0] as usize).min(bins - 1),
        (f[1] as usize).min(bins - 1),
        (f[2] as usize).min(bins - 1),
    ]
}

/// The best binned-SAH split, partitioning `refs` in place; `None` where
/// the SAH cannot separate the node (see the module docs). Nodes of fewer
/// than 64 references use at most 8 bins, of fewer than 1024 at most 32.
fn sah_split(
    refs: &mut [Ref],
    bounds: &Aabb,
    cbounds: &Aabb,
    bins: usize,
    scratch: &mut Scratch,
) -> Option<usize> {
    let Scratch {
        bins8,
        bins32,
        bins255,
        right_area,
        right_count,
    } = scratch;
    let sweep = (&mut right_area[..], &mut right_count[..]);
    match refs.len() {
        0..64 => sah_split_n(refs, bounds, cbounds, bins.min(8), bins8, sweep),
        64..1024 => sah_split_n(refs, bounds, cbounds, bins.min(32), bins32, sweep),
        _ => sah_split_n(refs, bounds, cbounds, bins, bins255, sweep),
    }
}

fn sah_split_n<const N: usize>(
    refs: &mut [Ref],
    bounds: &Aabb,
    cbounds: &Aabb,
    bins: usize,
    scratch: &mut Bins<N>,
    (right_area, right_count): (&mut [f32], &mut [u32]),
) -> Option<usize> {
    let ext = cbounds.extent();
    let usable = |a: usize| ext[a] > 0.0 && ext[a].is_finite();
    if !(0..3).any(usable) {
        return None;
    }
    // Flat axes get scale 0: everything lands in bin 0 and no split is found.
    let scale = Vec3A::from_array(std::array::from_fn(|a| {
        if usable(a) { bins as f32 / ext[a] } else { 0.0 }
    }));
    let lo = cbounds.min;
    let parallel;
    let binned: &Bins<N> = if refs.len() > PARALLEL_BINNING {
        parallel = refs
            .par_chunks(PARALLEL_BINNING / 4)
            .fold(
                || Box::new(Bins::<N>::new()),
                |mut acc, chunk| {
                    acc.fill(chunk, lo, scale, bins);
                    acc
                },
            )
            .reduce(
                || Box::new(Bins::<N>::new()),
                |a, b| Box::new(a.merge(&b, bins)),
            );
        &parallel
    } else {
        scratch.clear(bins);
        scratch.fill(refs, lo, scale, bins);
        scratch
    };
    // (cost, |left count - right count|, axis, split bin)
    let mut best: Option<(f32, u32, usize, usize)> = None;
    for axis in (0..3).filter(|&a| usable(a)) {
        let (counts, boxes) = (&binned.counts[axis], &binned.boxes[axis]);
        // Sweep from the right: area and count of bins [i, bins).
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in (1..bins).rev() {
            acc = acc.union(&boxes[i]);
            cnt += counts[i];
            right_area[i] = acc.half_area();
            right_count[i] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in 1..bins {
            acc = acc.union(&boxes[i - 1]);
            cnt += counts[i - 1];
            if cnt == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = acc.half_area() * cnt as f32 + right_area[i] * right_count[i] as f32;
            let imbalance = cnt.abs_diff(right_count[i]);
            let better = match best {
                None => cost.is_finite(),
                Some((c, im, _, _)) => cost < c || (cost == c && imbalance < im),
            };
            if better {
                best = Some((cost, imbalance, axis, i));
            }
        }
    }
    let (cost, _, axis, split) = best?;
    // Two references have one partition whatever the rule: keep the SAH's
    // order. The comparison is written so that a NaN bound (an overflowing
    // area) also gives `None`.
    let gains = cost < bounds.half_area() * refs.len() as f32 * (1.0 - MIN_SAH_GAIN);
    if !gains && refs.len() > 2 {
        return None;
    }
    // In-place partition: bins [0, split) to the left, with the same bin
    // arithmetic as the binning pass.
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        if bin_index(refs[i].centroid(), lo, scale, bins)[axis] < split {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    Some(i)
}
