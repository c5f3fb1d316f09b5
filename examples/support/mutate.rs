//! The mutation harness for every codec's file, shared by the test suite
//! (`tests/mutation.rs`, a short run) and `examples/mutate.rs` (a long run
//! that prints the table). It knows no codec's layout: it reads a file's
//! section table through the codec's [`Frame`] (`CodecKind::frame`), and
//! attacks any codec the registry names.
//!
//! Attacks:
//! - truncations and raw bit flips (no checksum recomputed): must be
//!   refused, or give the original file back;
//! - bit flips with every checksum recomputed, anywhere in the file;
//! - every 4-byte word of the header's fields forged with values that
//!   break counts, flags, grids and mass (huge, zero, negative, NaN, ×2,
//!   ×10³⁰), checksums recomputed;
//! - every section-table entry forged (offsets and lengths past the end,
//!   zero, overlapping the previous section), checksums recomputed;
//! - the first words of every section (a root node's box, a high-level
//!   root, a grid) forged with the header's values, checksums recomputed;
//! - structurally corrupt trees written by the codec's own encoder from a
//!   corrupted canonical tree (a child named twice, a node with two
//!   parents, a deep DAG), where the encoder takes them.
//!
//! How a case may end: the reader refuses it, `verify` refuses it, or the
//! file is accepted and is either the original (same decoded mesh, mass,
//! edge flags, root box and answers to fixed rays and boxes) or a
//! *consistent* other file: one whose answers are those of its own decoded
//! mesh (brute force), whose root box is tight around it and whose mass is
//! physical. A forger who recomputes checksums can write any consistent
//! file, so those are allowed where checksums were recomputed; a file
//! that is accepted and *inconsistent* (answers that disagree with its own
//! triangles, a root box looser than the mesh, a vertex beyond the
//! coordinate limit, an impossible mass) is
//! always a bug, as is a panic. A header forgery that is accepted with the
//! original's answers is an *ignored* header word (a reserved word, a
//! flag the reader does not check): also a bug.

#![allow(dead_code)] // each includer uses what it needs

use std::panic::{AssertUnwindSafe, catch_unwind};

use cbvh::codec::common::container::Frame;
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind, OpenOptions};
use cbvh::geom::{Aabb, Ray, Triangle, ray_triangle};
use cbvh::{CanonicalBvh, Mesh, TraversalStats};
use glam::Vec3A;
use xxhash_rust::xxh3::xxh3_64;

/// A small deterministic generator.
pub struct Rng(pub u64);

/// Words forged at the start of each section ([`Subject::run`]).
const SECTION_HEAD_WORDS: usize = 16;

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// How one case ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The reader refused the bytes.
    OpenError,
    /// `verify` refused them.
    VerifyError,
    /// Accepted, and the original file in every answer.
    Same,
    /// Accepted: another file, consistent with its own triangles.
    Consistent,
    /// Accepted, but answers, root box or mass disagree with the file's
    /// own triangles: always a bug.
    Inconsistent,
    /// A panic: always a bug.
    Panic,
}

/// One row of the table.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub codec: String,
    pub attack: &'static str,
    /// Attacks that leave the checksums as they are: every change must be
    /// refused.
    pub must_catch: bool,
    /// Header-word forgeries: a change the reader neither refuses nor
    /// uses (accepted with the original's answers) is an ignored word.
    pub no_ignored: bool,
    pub cases: usize,
    pub open_error: usize,
    pub verify_error: usize,
    pub same: usize,
    pub consistent: usize,
    pub inconsistent: usize,
    pub panic: usize,
    /// Header-word forgeries accepted with the original's answers.
    pub ignored: usize,
    /// Where the first failing case of this row changed the file (for the
    /// report): a byte offset and a note.
    pub first_bad: Option<String>,
    /// With an allocation probe ([`Subject::probe`]): the largest single
    /// allocation of any case of the row, and that case.
    pub largest_alloc: Option<(usize, String)>,
}

impl Row {
    /// Whether every case ended acceptably.
    pub fn ok(&self) -> bool {
        self.panic == 0
            && self.inconsistent == 0
            && (!self.must_catch || self.consistent == 0)
            && (!self.no_ignored || self.ignored == 0)
    }
}

/// Prints the rows as a Markdown table.
pub fn print_table(rows: &[Row]) {
    println!(
        "| codec | attack | cases | reader error | verify error | same | consistent other file | ignored header word | inconsistent | panic | first bad case |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    for r in rows {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.codec,
            r.attack,
            r.cases,
            r.open_error,
            r.verify_error,
            r.same,
            r.consistent,
            r.ignored,
            r.inconsistent,
            r.panic,
            r.first_bad.as_deref().unwrap_or("")
        );
    }
}

/// What a file answers: closest hits of fixed rays (t, as bits), the
/// triangles overlapping fixed boxes, and what a consumer reads besides
/// (the decoded mesh, the root box, the mass, the edge flags, and the
/// header fields `cbvh info` prints: a statistic the header stores is
/// read there, so a forged one is another file, not an ignored word).
#[derive(Clone, Debug, PartialEq)]
pub struct Answers {
    hits: Vec<Option<u32>>,
    overlaps: Vec<Vec<u32>>,
    mesh: (Vec<[u32; 3]>, Vec<[u32; 3]>),
    root: [u32; 6],
    mass: Vec<u8>,
    flags: Vec<u8>,
    info: Vec<(&'static str, String)>,
}

fn bits(a: &Aabb) -> [u32; 6] {
    let (l, h) = (a.min, a.max);
    [l.x, l.y, l.z, h.x, h.y, h.z].map(f32::to_bits)
}

fn answers(c: &AnyCodec, rays: &[Ray], boxes: &[Aabb]) -> Answers {
    let mut st = TraversalStats::default();
    let (hits, overlaps, root) = cbvh::with_codec!(c, |c| {
        let hits = rays
            .iter()
            .map(|r| cbvh::query::closest_hit(c, r, f32::INFINITY, &mut st).map(|h| h.t.to_bits()))
            .collect();
        let overlaps = boxes
            .iter()
            .map(|b| {
                let mut ids = Vec::new();
                cbvh::query::overlap(c, b, &mut st, |id, _| {
                    ids.push(id);
                    std::ops::ControlFlow::Continue(())
                });
                ids.sort_unstable();
                ids
            })
            .collect();
        (hits, overlaps, cbvh::NodeCursor::root(c).1)
    });
    let m = c.decoded_mesh();
    Answers {
        hits,
        overlaps,
        mesh: (
            m.vertices.iter().map(|v| v.map(f32::to_bits)).collect(),
            m.triangles.clone(),
        ),
        root: bits(&root),
        mass: c.mass().to_bytes().to_vec(),
        flags: c.edge_flags().as_slice().to_vec(),
        info: c.header_fields(),
    }
}

/// Why an accepted file is inconsistent with its own triangles, if it is:
/// a decoded vertex beyond the coordinate limit every encoder enforces
/// ([`cbvh::mesh::MAX_COORDINATE`]), answers that brute force over its
/// decoded mesh does not give, a root box not tight around the mesh
/// (within 1 % of its diagonal: the grid of a quantized codec rounds
/// outwards), or an impossible mass.
fn inconsistency(a: &Answers, rays: &[Ray], boxes: &[Aabb]) -> Option<String> {
    let verts: Vec<Vec3A> = a
        .mesh
        .0
        .iter()
        .map(|v| Vec3A::from(v.map(f32::from_bits)))
        .collect();
    if let Some(v) = verts
        .iter()
        .find(|v| !v.is_finite() || v.abs().max_element() > cbvh::mesh::MAX_COORDINATE)
    {
        return Some(format!("a decoded vertex {v} beyond the coordinate limit"));
    }
    let tris: Vec<Triangle> = a
        .mesh
        .1
        .iter()
        .map(|t| t.map(|i| verts[i as usize]))
        .collect();
    for (k, ray) in rays.iter().enumerate() {
        let mut best = f32::INFINITY;
        let mut hit = None;
        for tri in &tris {
            if let Some(h) = ray_triangle(ray, tri, best) {
                best = h.t;
                hit = Some(h.t.to_bits());
            }
        }
        if hit != a.hits[k] {
            return Some(format!("ray {k}: {:?}, brute force {hit:?}", a.hits[k]));
        }
    }
    for (k, b) in boxes.iter().enumerate() {
        let ids: Vec<u32> = (0..tris.len() as u32)
            .filter(|&i| Aabb::of_triangle(&tris[i as usize]).intersects(b))
            .collect();
        if ids != a.overlaps[k] {
            return Some(format!("box {k}: overlaps differ from brute force"));
        }
    }
    if let Some(first) = tris.first() {
        let mut bounds = Aabb::of_triangle(first);
        for t in &tris {
            bounds = bounds.union(&Aabb::of_triangle(t));
        }
        let root = a.root.map(f32::from_bits);
        let slack = 0.01 * bounds.extent().length();
        for k in 0..3 {
            let (lo, hi) = (bounds.min[k], bounds.max[k]);
            // The root must contain the mesh (verify proves it) and not
            // reach beyond it by more than the slack.
            let tight = root[k] <= lo && root[3 + k] >= hi;
            let snug = lo - root[k] <= slack && root[3 + k] - hi <= slack;
            if !(tight && snug) {
                return Some(format!(
                    "root box {root:?} against the mesh's bounds {:?}..{:?}",
                    bounds.min, bounds.max
                ));
            }
        }
    }
    let f = |k: usize| f32::from_le_bytes(a.mass[4 * k..4 * k + 4].try_into().unwrap());
    let mass = f(0);
    let inertia: Vec<f32> = (4..13).map(f).collect();
    if !(mass.is_finite() && mass >= 0.0) {
        return Some(format!("mass {mass}"));
    }
    if mass > 0.0 {
        // A physical inertia tensor: symmetric, positive diagonal, each
        // principal moment at most the sum of the other two.
        let (xx, yy, zz) = (inertia[0], inertia[4], inertia[8]);
        let sym = (inertia[1] - inertia[3]).abs() <= 1e-3 * (xx + yy + zz)
            && (inertia[2] - inertia[6]).abs() <= 1e-3 * (xx + yy + zz)
            && (inertia[5] - inertia[7]).abs() <= 1e-3 * (xx + yy + zz);
        let tol = 1e-3 * (xx + yy + zz);
        let triangle = xx <= yy + zz + tol && yy <= xx + zz + tol && zz <= xx + yy + tol;
        if !(xx > 0.0 && yy > 0.0 && zz > 0.0 && sym && triangle) {
            return Some(format!("inertia {inertia:?} for mass {mass}"));
        }
    }
    None
}

/// A codec's file under attack.
pub struct Subject {
    pub kind: CodecKind,
    /// The cache budget the file is opened with (o-HCCMesh pages its
    /// trees when its decoded form does not fit).
    pub budget: usize,
    /// The codec's name and the variant's settings.
    pub label: String,
    pub bytes: Vec<u8>,
    pub frame: Frame,
    rays: Vec<Ray>,
    boxes: Vec<Aabb>,
    want: Answers,
    /// Returns the largest single allocation since it was last called, and
    /// starts counting afresh: set by an includer with a recording global
    /// allocator, so that each case's largest allocation is known.
    pub probe: Option<fn() -> usize>,
}

fn open(kind: CodecKind, b: &[u8], budget: usize) -> Result<AnyCodec, String> {
    let options = OpenOptions {
        verify: false,
        cache_budget_bytes: budget,
    };
    AnyCodec::from_bytes(kind, b, &options).map_err(|e| e.to_string())
}

impl Subject {
    /// The file of `kind` in `bytes` (`label` names the variant), with the
    /// answers of the original.
    pub fn new(kind: CodecKind, label: String, bytes: Vec<u8>, budget: usize) -> Self {
        let c = open(kind, &bytes, budget).expect("the original opens");
        c.verify().expect("the original verifies");
        let b = cbvh::with_codec!(&c, |c| cbvh::NodeCursor::root(c).1);
        let (lo, hi) = (b.min, b.max);
        let mut rng = Rng(0x5eed);
        let pt = |rng: &mut Rng| {
            let f = |rng: &mut Rng| (rng.next() % 1000) as f32 / 1000.0;
            lo + (hi - lo) * Vec3A::new(f(rng), f(rng), f(rng))
        };
        let c0 = (lo + hi) * 0.5;
        let r = (hi - lo).length();
        let rays: Vec<Ray> = (0..48)
            .map(|k| {
                let target = pt(&mut rng);
                let a = k as f32 * 0.7;
                let origin = c0 + Vec3A::new(a.cos(), 0.3 * a.sin(), a.sin()) * r;
                Ray::new(origin, (target - origin).normalize())
            })
            .collect();
        let boxes: Vec<Aabb> = (0..6)
            .map(|_| {
                let p = pt(&mut rng);
                Aabb::new(p - (hi - lo) * 0.08, p + (hi - lo) * 0.08)
            })
            .collect();
        let want = answers(&c, &rays, &boxes);
        if let Some(why) = inconsistency(&want, &rays, &boxes) {
            panic!("{label}: the original is inconsistent: {why}");
        }
        Self {
            kind,
            budget,
            label,
            frame: kind.frame(),
            bytes,
            rays,
            boxes,
            want,
            probe: None,
        }
    }

    /// How `bytes` end (and, for an inconsistent file, why).
    pub fn outcome(&self, bytes: &[u8]) -> (Outcome, Option<String>) {
        self.outcome_probed(bytes).0
    }

    /// The largest single allocation of opening, verifying and querying
    /// `bytes` (0 without a probe).
    pub fn largest_allocation(&self, bytes: &[u8]) -> usize {
        self.outcome_probed(bytes).1
    }

    /// [`outcome`](Self::outcome), with the largest single allocation of
    /// opening, verifying and querying the file (not of the brute force
    /// that checks an accepted other file) if there is a probe.
    fn outcome_probed(&self, bytes: &[u8]) -> ((Outcome, Option<String>), usize) {
        let probe = || self.probe.map_or(0, |p| p());
        probe();
        let mut largest = 0;
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            match open(self.kind, bytes, self.budget) {
                Err(_) => (Outcome::OpenError, None),
                Ok(c) => match c.verify() {
                    Err(_) => (Outcome::VerifyError, None),
                    Ok(()) => {
                        let got = answers(&c, &self.rays, &self.boxes);
                        largest = probe();
                        if got == self.want {
                            (Outcome::Same, None)
                        } else if let Some(why) = inconsistency(&got, &self.rays, &self.boxes) {
                            (Outcome::Inconsistent, Some(why))
                        } else {
                            (Outcome::Consistent, None)
                        }
                    }
                },
            }
        }))
        .unwrap_or((Outcome::Panic, None));
        if largest == 0 {
            largest = probe();
        }
        (outcome, largest)
    }

    fn row(
        &self,
        attack: &'static str,
        must_catch: bool,
        no_ignored: bool,
        cases: Vec<(Vec<u8>, String)>,
    ) -> Row {
        let mut row = Row {
            codec: self.label.clone(),
            attack,
            must_catch,
            no_ignored,
            ..Default::default()
        };
        for (case, what) in cases {
            row.cases += 1;
            let ((outcome, why), size) = self.outcome_probed(&case);
            if self.probe.is_some() && row.largest_alloc.as_ref().is_none_or(|(s, _)| size > *s) {
                row.largest_alloc = Some((size, what.clone()));
            }
            let bad = match outcome {
                Outcome::OpenError => {
                    row.open_error += 1;
                    false
                }
                Outcome::VerifyError => {
                    row.verify_error += 1;
                    false
                }
                Outcome::Same => {
                    row.same += 1;
                    row.ignored += usize::from(no_ignored);
                    no_ignored
                }
                Outcome::Consistent => {
                    row.consistent += 1;
                    must_catch
                }
                Outcome::Inconsistent => {
                    row.inconsistent += 1;
                    true
                }
                Outcome::Panic => {
                    row.panic += 1;
                    true
                }
            };
            if std::env::var_os("MUTATE_TRACE").is_some() && bad {
                eprintln!(
                    "{}: {what}: {outcome:?} {}",
                    self.label,
                    why.clone().unwrap_or_default()
                );
            }
            if bad && row.first_bad.is_none() {
                row.first_bad = Some(format!("{what}: {outcome:?} {}", why.unwrap_or_default()));
            }
        }
        row
    }

    /// Recomputes every checksum of `b`: the codec's own ones inside its
    /// sections (RACBVH's per-cluster checksums), then the frame's.
    pub fn reseal(&self, b: &mut [u8]) {
        if self.kind == CodecKind::Racbvh {
            reseal_clusters(b, &self.frame);
        }
        self.frame.reseal(b);
    }

    /// Runs every byte-level attack, `n` cases for the random ones.
    pub fn run(&self, n: usize, seed: u64) -> Vec<Row> {
        let mut rng = Rng(seed | 1);
        let len = self.bytes.len();
        let header = self.frame.header_len();
        let mut rows = Vec::new();
        // Truncations.
        let cuts = [0, 1, 7, 8, 12, header - 1, header, header + 1]
            .into_iter()
            .chain((0..n).map(|_| rng.below(len)))
            .chain([len - 1])
            .filter(|&c| c < len)
            .map(|c| (self.bytes[..c].to_vec(), format!("cut at {c}")))
            .collect();
        rows.push(self.row("truncation", true, false, cuts));
        // Raw bit flips.
        let flip = |rng: &mut Rng, b: &mut Vec<u8>| {
            let at = rng.below(b.len());
            b[at] ^= 1 << rng.below(8);
            at
        };
        let raw = (0..n)
            .map(|_| {
                let mut b = self.bytes.clone();
                let at = flip(&mut rng, &mut b);
                (b, format!("bit flip at {at}"))
            })
            .collect();
        rows.push(self.row("raw bit flip", true, false, raw));
        // Bit flips, checksums recomputed.
        let sealed = (0..n)
            .map(|_| {
                let mut b = self.bytes.clone();
                let at: Vec<usize> = (0..1 + rng.below(3))
                    .map(|_| flip(&mut rng, &mut b))
                    .collect();
                self.reseal(&mut b);
                (b, format!("bit flips at {at:?}"))
            })
            .collect();
        rows.push(self.row("bit flips, checksums recomputed", false, false, sealed));
        // Forged header words.
        // Every value for every word in a long run, a few in a short one.
        let per_word = if n >= 100 { usize::MAX } else { 1 + n / 4 };
        let forged = self.forged_words(per_word, &mut rng);
        rows.push(self.row("forged header word (checksummed)", false, true, forged));
        // Forged section tables.
        let tables = self.forged_tables();
        rows.push(self.row("forged section table (checksummed)", false, false, tables));
        // Forged words at the start of each section, where the root's box
        // and the grids live.
        let heads = self.forged_section_heads(per_word, &mut rng);
        rows.push(self.row("forged section head (checksummed)", false, false, heads));
        rows
    }

    /// Every 4-byte word of the header's fields (after the magic and the
    /// version) replaced by each of a set of hostile values (at most
    /// `per_word` of them, chosen with `rng`), the checksums recomputed.
    fn forged_words(&self, per_word: usize, rng: &mut Rng) -> Vec<(Vec<u8>, String)> {
        self.forged_at((12..self.frame.table).step_by(4), per_word, rng)
    }

    /// The first [`SECTION_HEAD_WORDS`] 4-byte words of every section (a
    /// plain or clbvh root node's box, the i-HCCMesh high-level root, a
    /// grid's origin and steps) forged as [`Self::forged_words`] forges
    /// the header's: a root box made looser, a grid stretched.
    fn forged_section_heads(&self, per_word: usize, rng: &mut Rng) -> Vec<(Vec<u8>, String)> {
        let mut at = Vec::new();
        for k in 0..self.frame.sections.len() {
            let (off, len, _) = self.frame.entry(&self.bytes, k);
            let (off, len) = (off as usize, len as usize);
            at.extend((off..off + len.min(4 * SECTION_HEAD_WORDS)).step_by(4));
        }
        at.retain(|&a| a + 4 <= self.bytes.len());
        self.forged_at(at.into_iter(), per_word, rng)
    }

    /// The words at `at` forged with hostile values, each file resealed.
    fn forged_at(
        &self,
        at: impl Iterator<Item = usize>,
        per_word: usize,
        rng: &mut Rng,
    ) -> Vec<(Vec<u8>, String)> {
        let mut out = Vec::new();
        for at in at {
            let old = u32::from_le_bytes(self.bytes[at..at + 4].try_into().unwrap());
            let f = f32::from_bits(old);
            let mut vals = vec![
                0,
                1,
                old ^ 1,
                old.wrapping_add(1),
                old.wrapping_sub(1),
                old ^ 0x8000_0000,
                u32::MAX,
                1 << 31,
                (1 << 31) - 1,
                1 << 24,
                old.wrapping_mul(2),
            ];
            if f.is_finite() {
                vals.extend(
                    [
                        f * 2.0,
                        f * 0.5,
                        f + 0.25,
                        -f,
                        f * 1e30,
                        f32::NAN,
                        f32::INFINITY,
                    ]
                    .map(f32::to_bits),
                );
            }
            vals.sort_unstable();
            vals.dedup();
            vals.retain(|&v| v != old);
            // A short run forges each word with a few of the values, chosen
            // at random.
            while vals.len() > per_word {
                vals.swap_remove(rng.below(vals.len()));
            }
            for v in vals {
                let mut b = self.bytes.clone();
                b[at..at + 4].copy_from_slice(&v.to_le_bytes());
                self.reseal(&mut b);
                out.push((b, format!("word at {at}: {old:#x} -> {v:#x}")));
            }
        }
        out
    }

    /// Each section-table entry's offset and length forged, checksums
    /// recomputed.
    fn forged_tables(&self) -> Vec<(Vec<u8>, String)> {
        let len = self.bytes.len() as u64;
        let mut out = Vec::new();
        for k in 0..self.frame.sections.len() {
            let at = self.frame.table + 24 * k;
            let (off, slen, _) = self.frame.entry(&self.bytes, k);
            let mut put = |field: usize, v: u64| {
                let mut b = self.bytes.clone();
                b[at + field..at + field + 8].copy_from_slice(&v.to_le_bytes());
                self.frame.reseal(&mut b);
                out.push((
                    b,
                    format!("section {k} {} = {v}", ["offset", "length"][field / 8]),
                ));
            };
            for v in [
                len,
                len + 1,
                u64::MAX,
                u64::MAX - 7,
                0,
                8,
                off + 1,
                off.wrapping_sub(1),
            ] {
                put(0, v);
            }
            for v in [
                len,
                len + 1,
                u64::MAX,
                u64::MAX - 7,
                0,
                8,
                slen + 1,
                slen.wrapping_sub(1),
            ] {
                put(8, v);
            }
        }
        out
    }

    /// Files written by the codec's own encoder from canonical trees with
    /// one structural defect each (a child named twice, a node adopted by
    /// a second parent, a path of children named twice: a DAG), so that
    /// every checksum and bit is as the codec writes them; trees the
    /// encoder refuses (or panics on: the canonical tree is trusted input)
    /// are skipped (hcc and hcc-ooc check the tree first and refuse them
    /// all). An encoder may also turn such a tree into a valid file of
    /// another mesh, so a consistent other file is allowed; an
    /// inconsistent one is not.
    pub fn corrupt_trees(
        &self,
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &AnyOptions,
        n: usize,
        seed: u64,
    ) -> Row {
        let mut rng = Rng(seed | 1);
        let inner: Vec<usize> = (0..bvh.nodes.len())
            .filter(|&i| !bvh.nodes[i].is_leaf())
            .collect();
        let mut cases = Vec::new();
        for k in 0..n {
            let mut t = bvh.clone();
            let i = inner[rng.below(inner.len())];
            let j = inner[rng.below(inner.len())];
            match k % 3 {
                0 => t.nodes[i].b = t.nodes[i].a,
                1 if i < j => {
                    let c = t.nodes[j].b;
                    if c as usize > i {
                        t.nodes[i].a = c;
                    }
                }
                _ => {
                    let mut x = i;
                    for _ in 0..64 {
                        if t.nodes[x].is_leaf() {
                            break;
                        }
                        let a = t.nodes[x].a;
                        t.nodes[x].b = a;
                        x = a as usize;
                    }
                }
            }
            let encoded = catch_unwind(AssertUnwindSafe(|| {
                AnyCodec::encode(self.kind, &t, mesh, options).ok()
            }));
            if let Ok(Some(c)) = encoded {
                cases.push((c.to_bytes(), format!("tree defect {}", k % 3)));
            }
        }
        self.row(
            "corrupt tree via the encoder (repeats, DAGs)",
            false,
            false,
            cases,
        )
    }
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// RACBVH's per-cluster checksums (the meta table, section 0: 20-byte
/// entries of cluster start u64, then at 12 the cluster's checksum),
/// recomputed over the clusters section (section 1); best effort on
/// garbage, never panics.
fn reseal_clusters(b: &mut [u8], frame: &Frame) {
    const ENTRY: usize = 20;
    if b.len() < frame.header_len() {
        return;
    }
    let range = |b: &[u8], k: usize| -> Option<std::ops::Range<usize>> {
        let (off, len, _) = frame.entry(b, k);
        let off = usize::try_from(off).ok()?;
        let end = off.checked_add(usize::try_from(len).ok()?)?;
        (end <= b.len()).then_some(off..end)
    };
    let (Some(m), Some(c)) = (range(b, 0), range(b, 1)) else {
        return;
    };
    let count = m.len() / ENTRY;
    for i in 0..count {
        let e = m.start + i * ENTRY;
        let start = u64_at(b, e).and_then(|x| usize::try_from(x).ok());
        let end = if i + 1 < count {
            u64_at(b, e + ENTRY).and_then(|x| usize::try_from(x).ok())
        } else {
            Some(c.len())
        };
        if let (Some(s), Some(t)) = (start, end)
            && s <= t
            && t <= c.len()
        {
            let h = xxh3_64(&b[c.start + s..c.start + t]);
            b[e + 12..e + 20].copy_from_slice(&h.to_le_bytes());
        }
    }
}

/// A codec variant to attack: the codec's name, the build's leaf size, its
/// `CODEC.KEY=VALUE` settings, and the cache budget it is opened with.
pub type Variant = (&'static str, usize, &'static [&'static str], usize);

/// The variants every run attacks: each codec of the registry with its
/// defaults ([`CodecKind::ALL`], so a new codec is attacked without a line
/// here), then [`EXTRA_VARIANTS`].
pub fn variants() -> Vec<Variant> {
    let defaults = CodecKind::ALL
        .iter()
        .map(|k| (k.name(), 1, &[][..], 1 << 20));
    defaults.chain(EXTRA_VARIANTS.iter().copied()).collect()
}

/// The options and modes that change a codec's layout or its reader,
/// beyond its defaults.
pub const EXTRA_VARIANTS: &[Variant] = &[
    ("plain", 4, &[], 1 << 20),
    // Clusters small enough that the test mesh spans many.
    ("racbvh", 1, &["racbvh.cluster-nodes=256"], 1 << 20),
    (
        "racbvh",
        4,
        &["racbvh.cluster-nodes=256", "racbvh.bits=12"],
        4096,
    ),
    ("clbvh", 1, &["clbvh.multi-leaf=false"], 1 << 20),
    ("hcc", 4, &["hcc.tree-order=true"], 1 << 20),
    ("hcc", 1, &["hcc.vertex-ids=false"], 1 << 20),
    // A budget too small for the decoded trees: paged out of core.
    ("hcc-ooc", 4, &[], 4096),
];

/// One variant's subject, its canonical tree and its options.
pub fn variant(
    mesh: &Mesh,
    (codec, leaf, sets, budget): Variant,
) -> (Subject, CanonicalBvh, AnyOptions) {
    let kind: CodecKind = codec.parse().unwrap();
    let mut settings = cbvh::codec::Settings::new(leaf, None);
    for s in sets {
        settings.set(s).unwrap();
    }
    let options = AnyOptions::from_settings(&settings, &[kind]).unwrap();
    let build = cbvh::build::BuildOptions {
        max_leaf_triangles: leaf,
        ..Default::default()
    };
    let bvh = cbvh::build::build(mesh, &build, &|_, _| {}).unwrap();
    let bytes = AnyCodec::encode(kind, &bvh, mesh, &options)
        .unwrap()
        .to_bytes();
    let mut label = codec.to_string();
    if leaf > 1 {
        label += &format!(" leaf {leaf}");
    }
    for s in sets {
        label += &format!(" {}", s.split_once('.').map_or(*s, |(_, kv)| kv));
    }
    if budget < 1 << 20 {
        label += &format!(" cache {budget} B");
    }
    (Subject::new(kind, label, bytes, budget), bvh, options)
}
