//! The mutation harness for every codec file decoder, shared by the test
//! suite (`tests/mutation.rs`, a short run) and `examples/mutate.rs` (a long
//! run that prints the table).
//!
//! Attacks: truncations; raw bit flips; bit flips with every checksum
//! recomputed; forged headers (huge counts, offsets past the end,
//! overlapping sections, bad grids and mass), checksums recomputed;
//! structurally corrupt but checksummed trees (repeated children, cycles,
//! boxes outside their parent, leaves that do not contain their triangle,
//! a triangle in two leaves). Every case must end in an error from the
//! reader, in `verify` catching it, or in answers identical to the original
//! file's; with checksums recomputed a file may also be a *consistent*
//! different file (every proof of `verify` holds, the answers differ: a
//! forger who recomputes checksums can write any valid file). Never a
//! panic, a hang, or, for the attacks marked `must_catch`, a different
//! answer.

#![allow(dead_code)] // each includer uses what it needs

use std::panic::{AssertUnwindSafe, catch_unwind};

use cbvh::TraversalStats;
use cbvh::codec::racbvh::RacBvh;
use cbvh::codec::{AnyCodec, OpenOptions};
use cbvh::geom::{Aabb, Ray};
use glam::Vec3A;
use xxhash_rust::xxh3::xxh3_64;

/// Sections of the plain and RACBVH files (the last one the edge flags).
const SECTIONS: usize = 5;

/// A small deterministic generator.
pub struct Rng(pub u64);

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
    /// Verified, and every answer equals the original file's.
    Same,
    /// Verified, answers differ: a consistent different file (only allowed
    /// where checksums were recomputed).
    Consistent,
    /// A panic: always a bug.
    Panic,
}

/// One row of the table.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub codec: &'static str,
    pub attack: &'static str,
    pub must_catch: bool,
    pub cases: usize,
    pub open_error: usize,
    pub verify_error: usize,
    pub same: usize,
    pub consistent: usize,
    pub panic: usize,
}

impl Row {
    /// Whether every case ended acceptably.
    pub fn ok(&self) -> bool {
        self.panic == 0 && (!self.must_catch || self.consistent == 0)
    }
}

/// Prints the rows as a Markdown table.
pub fn print_table(rows: &[Row]) {
    println!(
        "| codec | attack | cases | reader error | verify error | same answers | consistent other file | panic |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            r.codec, r.attack, r.cases, r.open_error, r.verify_error, r.same, r.consistent, r.panic
        );
    }
}

/// What a file answers: closest hits of fixed rays, and the triangles
/// overlapping fixed boxes.
#[derive(Clone, Debug, PartialEq)]
pub struct Answers(Vec<Option<(u32, u32)>>, Vec<Vec<u32>>, usize);

fn answers_of<C: cbvh::NodeCursor>(c: &C, rays: &[Ray], boxes: &[Aabb]) -> Answers {
    let mut st = TraversalStats::default();
    let hits = rays
        .iter()
        .map(|r| {
            cbvh::query::closest_hit(c, r, f32::INFINITY, &mut st)
                .map(|h| (h.triangle, h.t.to_bits()))
        })
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
    Answers(hits, overlaps, c.triangle_count())
}

fn answers(c: &AnyCodec, rays: &[Ray], boxes: &[Aabb]) -> Answers {
    cbvh::with_codec!(c, |c| answers_of(c, rays, boxes))
}

/// A codec file under attack.
pub struct Subject {
    pub codec: &'static str,
    pub bytes: Vec<u8>,
    rays: Vec<Ray>,
    boxes: Vec<Aabb>,
    want: Answers,
}

fn open(codec: &str, b: &[u8]) -> Result<AnyCodec, String> {
    let kind = codec.parse().map_err(|e| format!("{e}"))?;
    let options = OpenOptions {
        verify: false,
        cache_budget_bytes: 1 << 20,
    };
    AnyCodec::from_bytes(kind, b, &options).map_err(|e| e.to_string())
}

impl Subject {
    /// The file of `codec` ("plain" or "racbvh") in `bytes`, with the
    /// answers of the original.
    pub fn new(codec: &'static str, bytes: Vec<u8>) -> Self {
        let c = open(codec, &bytes).expect("the original opens");
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
        Self {
            codec,
            bytes,
            rays,
            boxes,
            want,
        }
    }

    /// How `bytes` end.
    pub fn outcome(&self, bytes: &[u8]) -> Outcome {
        catch_unwind(AssertUnwindSafe(|| match open(self.codec, bytes) {
            Err(_) => Outcome::OpenError,
            Ok(c) => match c.verify() {
                Err(_) => Outcome::VerifyError,
                Ok(()) if answers(&c, &self.rays, &self.boxes) == self.want => Outcome::Same,
                Ok(()) => Outcome::Consistent,
            },
        }))
        .unwrap_or(Outcome::Panic)
    }

    fn row(&self, attack: &'static str, must_catch: bool, cases: Vec<Vec<u8>>) -> Row {
        let mut row = Row {
            codec: self.codec,
            attack,
            must_catch,
            ..Default::default()
        };
        for case in cases {
            row.cases += 1;
            match self.outcome(&case) {
                Outcome::OpenError => row.open_error += 1,
                Outcome::VerifyError => row.verify_error += 1,
                Outcome::Same => row.same += 1,
                Outcome::Consistent => row.consistent += 1,
                Outcome::Panic => row.panic += 1,
            }
        }
        row
    }

    /// Recomputes every checksum of `b` (best effort: never panics on
    /// garbage), so that an attack reaches the checks behind them.
    pub fn reseal(&self, b: &mut [u8]) {
        if self.codec == "plain" {
            reseal(b, 216, 88, None);
        } else {
            reseal(b, 312, 184, Some(20));
        }
    }

    /// Runs every attack with `n` cases for the random ones.
    pub fn run(&self, n: usize, seed: u64) -> Vec<Row> {
        let mut rng = Rng(seed | 1);
        let len = self.bytes.len();
        let mut rows = Vec::new();
        // Truncations.
        let cuts: Vec<Vec<u8>> = [0, 1, 7, 8, 100, 215, 216, 311, 312]
            .into_iter()
            .chain((0..n).map(|_| rng.below(len)))
            .chain([len - 1])
            .filter(|&c| c < len)
            .map(|c| self.bytes[..c].to_vec())
            .collect();
        rows.push(self.row("truncation", true, cuts));
        // Raw bit flips.
        let flip = |rng: &mut Rng, b: &mut Vec<u8>| {
            let at = rng.below(b.len());
            b[at] ^= 1 << rng.below(8);
        };
        let raw: Vec<Vec<u8>> = (0..n)
            .map(|_| {
                let mut b = self.bytes.clone();
                flip(&mut rng, &mut b);
                b
            })
            .collect();
        rows.push(self.row("raw bit flip", true, raw));
        // Bit flips, checksums recomputed.
        let sealed: Vec<Vec<u8>> = (0..n)
            .map(|_| {
                let mut b = self.bytes.clone();
                for _ in 0..1 + rng.below(3) {
                    flip(&mut rng, &mut b);
                }
                self.reseal(&mut b);
                b
            })
            .collect();
        rows.push(self.row("bit flips, checksums recomputed", false, sealed));
        // Forged headers.
        let forged: Vec<Vec<u8>> = self
            .forgeries()
            .into_iter()
            .map(|(at, v)| {
                let mut b = self.bytes.clone();
                b[at..at + v.len()].copy_from_slice(&v);
                self.reseal_header_only(&mut b);
                b
            })
            .collect();
        rows.push(self.row("forged header (checksummed)", false, forged));
        // Structurally corrupt, checksummed trees.
        if self.codec == "plain" {
            let trees = self.corrupt_plain_trees(n, &mut rng);
            rows.push(self.row(
                "corrupt tree, checksummed (repeats, cycles, boxes)",
                true,
                trees,
            ));
        }
        rows
    }

    /// RACBVH files whose trees are structurally corrupt, written by the
    /// real encoder (so every checksum and every bit is as the codec writes
    /// it): an inner node naming one child twice, a node adopted by a
    /// second parent (a DAG: the hang and million-triangle
    /// overlap), or a child moved before its parent; cases the encoder
    /// refuses are skipped.
    pub fn racbvh_corrupt_trees(
        &self,
        bvh: &cbvh::CanonicalBvh,
        mesh: &cbvh::Mesh,
        opts: &cbvh::codec::racbvh::RacOptions,
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
                    // j's right child becomes i's left child too (two parents),
                    // in a later cluster when possible.
                    let c = t.nodes[j].b;
                    if c as usize > i {
                        t.nodes[i].a = c;
                    }
                }
                _ => {
                    // A deep DAG: every inner node on a path names its left
                    // child twice.
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
            if let Ok(r) = RacBvh::encode(&t, mesh, opts) {
                cases.push(r.to_bytes());
            }
        }
        self.row("corrupt tree via the encoder (repeats, DAGs)", true, cases)
    }

    fn reseal_header_only(&self, b: &mut [u8]) {
        let h = if self.codec == "plain" { 216 } else { 312 };
        let sum = xxh3_64(&b[..h - 8]);
        b[h - 8..h].copy_from_slice(&sum.to_le_bytes());
    }

    /// (byte offset, new bytes) for each forged header field.
    fn forgeries(&self) -> Vec<(usize, Vec<u8>)> {
        let len = self.bytes.len() as u64;
        let u32s = |at: usize, vals: &[u32]| -> Vec<(usize, Vec<u8>)> {
            vals.iter()
                .map(|v| (at, v.to_le_bytes().to_vec()))
                .collect()
        };
        let mut out = Vec::new();
        let (table, counts): (usize, &[usize]) = if self.codec == "plain" {
            (88, &[16, 20, 24, 28])
        } else {
            (184, &[24, 28, 92])
        };
        for &c in counts {
            out.extend(u32s(c, &[0, 1, u32::MAX, 1 << 31, (1 << 31) - 1, 1 << 24]));
        }
        for k in 0..SECTIONS {
            let off = table + 24 * k;
            for v in [len, len + 1, u64::MAX, u64::MAX - 7, 0, 8] {
                out.push((off, v.to_le_bytes().to_vec()));
                out.push((off + 8, v.to_le_bytes().to_vec()));
            }
            if k > 0 {
                // Overlap the previous section.
                out.push((off, self.bytes[off - 24..off - 16].to_vec()));
            }
        }
        let nan = f32::NAN.to_le_bytes().to_vec();
        let mass = if self.codec == "plain" { 32 } else { 128 };
        out.push((mass, nan.clone()));
        out.push((mass, (-1.0f32).to_le_bytes().to_vec()));
        out.push((mass + 4, nan.clone()));
        if self.codec != "plain" {
            // Cluster bits, box bits, max leaf, threshold, vertex bits.
            out.extend(u32s(16, &[7, 14, 15, u32::MAX]));
            out.extend(u32s(20, &[7, 8, 24, 25]));
            out.extend(u32s(32, &[0, 2, 65537]));
            out.extend(u32s(88, &[7, 8, 24, 32, 33]));
            // The box grid and the vertex grid: shifted, scaled, NaN.
            for at in [40, 52, 100, 112] {
                let v = f32::from_le_bytes(self.bytes[at..at + 4].try_into().unwrap());
                for x in [v + 0.25, v * 2.0, v * 0.5, -v, f32::NAN, f32::INFINITY] {
                    out.push((at, x.to_le_bytes().to_vec()));
                }
            }
        }
        out
    }

    /// Plain trees with one structural defect each, checksums recomputed.
    fn corrupt_plain_trees(&self, n: usize, rng: &mut Rng) -> Vec<Vec<u8>> {
        let nodes = u32::from_le_bytes(self.bytes[16..20].try_into().unwrap()) as usize;
        let at = |i: usize| 216 + 32 * i;
        let word = |b: &[u8], i: usize, w: usize| {
            u32::from_le_bytes(b[at(i) + 4 * w..at(i) + 4 * w + 4].try_into().unwrap())
        };
        let put = |b: &mut [u8], i: usize, w: usize, v: u32| {
            b[at(i) + 4 * w..at(i) + 4 * w + 4].copy_from_slice(&v.to_le_bytes());
        };
        let inner: Vec<usize> = (0..nodes)
            .filter(|&i| word(&self.bytes, i, 7) & 0x8000_0000 == 0)
            .collect();
        let leaves: Vec<usize> = (0..nodes)
            .filter(|&i| word(&self.bytes, i, 7) & 0x8000_0000 != 0)
            .collect();
        let mut out = Vec::new();
        for k in 0..n {
            let mut b = self.bytes.clone();
            let i = inner[rng.below(inner.len())];
            let (l, r) = (word(&b, i, 6), word(&b, i, 7));
            match k % 7 {
                0 => put(&mut b, i, 7, l),                // the same child twice
                1 => put(&mut b, i, 6, 0),                // a cycle back to the root
                2 => put(&mut b, i, 6, i as u32),         // a self-loop
                3 => put(&mut b, i, 7, nodes as u32 + 5), // out of range
                4 => {
                    // A child box sticking out of its parent.
                    let c = l as usize;
                    let v = f32::from_bits(word(&b, c, 0)) - 1.0;
                    put(&mut b, c, 0, v.to_bits());
                    let _ = r;
                }
                5 => {
                    // A leaf box that misses its triangle (shrunk to a point).
                    let leaf = leaves[rng.below(leaves.len())];
                    for w in 3..6 {
                        let v = word(&b, leaf, w - 3);
                        put(&mut b, leaf, w, v);
                    }
                }
                _ => {
                    // A triangle in two leaves (another leaf's id).
                    let (a, c) = (
                        leaves[rng.below(leaves.len())],
                        leaves[rng.below(leaves.len())],
                    );
                    if a == c {
                        put(&mut b, i, 7, l);
                    } else {
                        let v = word(&b, a, 6);
                        put(&mut b, c, 6, v);
                    }
                }
            }
            self.reseal(&mut b);
            out.push(b);
        }
        out
    }
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// Recomputes the section checksums (and, with `meta`, the per-cluster
/// checksums in the first section's entries of `meta` bytes), then the
/// header's.
fn reseal(b: &mut [u8], header: usize, table: usize, meta: Option<usize>) {
    if b.len() < header {
        return;
    }
    let range = |b: &[u8], k: usize| -> Option<std::ops::Range<usize>> {
        let off = usize::try_from(u64_at(b, table + 24 * k)?).ok()?;
        let len = usize::try_from(u64_at(b, table + 24 * k + 8)?).ok()?;
        let end = off.checked_add(len)?;
        (end <= b.len()).then_some(off..end)
    };
    if let (Some(entry), Some(m), Some(c)) = (meta, range(b, 0), range(b, 1)) {
        let count = m.len() / entry;
        for i in 0..count {
            let e = m.start + i * entry;
            let start = u64_at(b, e).and_then(|x| usize::try_from(x).ok());
            let end = if i + 1 < count {
                u64_at(b, e + entry).and_then(|x| usize::try_from(x).ok())
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
    for k in 0..SECTIONS {
        if let Some(r) = range(b, k) {
            let h = xxh3_64(&b[r]);
            b[table + 24 * k + 16..table + 24 * k + 24].copy_from_slice(&h.to_le_bytes());
        }
    }
    let h = xxh3_64(&b[..header - 8]);
    b[header - 8..header].copy_from_slice(&h.to_le_bytes());
}
