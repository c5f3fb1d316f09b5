//! Cluster decompression (§5): a cluster's bytes, checked against its
//! checksum, into in-core nodes ([`Cluster`]), and clusters fetched through
//! the cache. What a cluster codes is in the module docs of [`super`].

use std::sync::{Arc, Mutex};

use super::node::{CoreNode, INCOMPLETE, apply, qbox_of};
use super::{
    CTX_CHILD, CTX_COUNT, CTX_PCLUSTER, CTX_STRUCT, CTX_TRI, CTX_TRI_FAR, Header, NCTX, RacBvh,
    RacError, STREAMS, mask_context, raw_bits, value_context,
};
use crate::build::LEAF_FLAG;
use crate::codec::common::FormatError;
use crate::codec::common::bits::{BitReader, unzigzag};
use crate::codec::common::dict::{DictDecoder, SymbolDecoder};
use crate::codec::common::page_cache::{Live, LiveToken, Page};
use crate::codec::common::quant::QBox;

/// In-core bytes per node of a decoded cluster (node + local-root ordinal).
pub const CLUSTER_BYTES_PER_NODE: usize = 34;

/// A local root: a node whose parent is in an earlier cluster.
#[derive(Clone, Copy, Debug)]
pub(super) struct LocalRoot {
    /// Its index in the cluster.
    pub(super) local: u32,
    /// Its parent's global index.
    pub(super) parent: u32,
    /// Whether it is its parent's right child.
    pub(super) right: bool,
}

/// A decompressed cluster.
pub struct Cluster {
    pub(super) first: u32,
    pub(super) nodes: Box<[CoreNode]>,
    /// Triangle ids of leaves holding several.
    pub(super) tris: Box<[u32]>,
    pub(super) roots: Box<[LocalRoot]>,
    /// Per node, the ordinal of its local root in `roots` (`u16::MAX` for
    /// the subtree of the global root).
    pub(super) root_of: Box<[u16]>,
    pub(super) lock: Mutex<()>,
    pub(super) live: LiveToken,
}

/// Decodes cluster `c` of `h` from `bytes` (the cluster's own bytes).
fn decode_cluster(
    h: &Header,
    c: u32,
    first: u32,
    n: u32,
    bytes: &[u8],
    live: &Arc<Live>,
) -> Result<Cluster, RacError> {
    let bad = |what| RacError::CorruptCluster { cluster: c, what };
    // The stream table: the byte lengths of all streams but the last.
    let table = 4 * (STREAMS - 1);
    if bytes.len() < table {
        return Err(bad("its stream table is truncated"));
    }
    let mut readers: [BitReader<'_>; STREAMS] = std::array::from_fn(|_| BitReader::new(&[]));
    let mut at = table;
    for (k, reader) in readers.iter_mut().enumerate() {
        let len = if k + 1 < STREAMS {
            let b = &bytes[4 * k..4 * k + 4];
            u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize
        } else {
            bytes.len() - at
        };
        if at.checked_add(len).is_none_or(|end| end > bytes.len()) {
            return Err(bad("a stream overruns the cluster"));
        }
        *reader = BitReader::with_limit(&bytes[at..], len);
        at += len;
    }
    let [mut r, mut rmask, mut rres @ ..] = readers;
    let from_oldest = r.get(1) == 1;
    let mut dec: [DictDecoder; NCTX] =
        std::array::from_fn(|ctx| DictDecoder::new(r.get(2) as u32, raw_bits(ctx, h)));
    let npc = r.get_golomb(0)?;
    if npc > n {
        return Err(bad("too many parent clusters"));
    }
    let mut pclusters = Vec::with_capacity(npc as usize);
    for _ in 0..npc {
        let d = r.get_golomb(0)?;
        if d >= c {
            return Err(bad("a parent cluster does not come before the cluster"));
        }
        pclusters.push(c - d - 1);
    }
    let n_us = n as usize;
    let mut words: Vec<[u32; 8]> = vec![[0; 8]; n_us];
    let mut got = vec![0u8; n_us];
    // Per node, which of its residuals are non-zero (the sibling's predict
    // the mask).
    let mut nonzero_of = vec![0u8; n_us];
    let mut root_of = vec![u16::MAX; n_us];
    let mut roots: Vec<LocalRoot> = Vec::new();
    let mut front: Vec<u32> = Vec::new();
    let mut tris: Vec<u32> = Vec::new();
    let mut last_tri: i64 = 0;
    let end = first + n;
    for l in 0..n_us {
        let g = first + l as u32;
        let s = dec[CTX_STRUCT].decode(&mut r)?;
        let leaf = s & 1 == 1;
        let mut right = s & 2 != 0;
        let pos = s >> 2;
        let mut complete_parent: Option<QBox> = None;
        let mut sibling: Option<usize> = None;
        if g == 0 {
            if s > 1 {
                return Err(bad("the root has a parent"));
            }
            let q = Header::root_qbox(&h.grid);
            words[0][..3].copy_from_slice(&q.min.to_array());
            words[0][3..6].copy_from_slice(&q.max.to_array());
        } else if pos == 0 {
            let pci = dec[CTX_PCLUSTER].decode(&mut r)?;
            let pc = *pclusters
                .get(pci as usize)
                .ok_or_else(|| bad("a parent-cluster index is out of range"))?;
            let parent = (pc << h.cluster_bits) | r.get(h.cluster_bits) as u32;
            if roots.len() >= usize::from(u16::MAX) {
                return Err(bad("too many local roots"));
            }
            root_of[l] = roots.len() as u16;
            roots.push(LocalRoot {
                local: l as u32,
                parent,
                right,
            });
        } else {
            let pos = pos as usize;
            let at = if from_oldest {
                Some(pos - 1)
            } else {
                front.len().checked_sub(pos)
            }
            .filter(|&at| at < front.len())
            .ok_or_else(|| bad("a front position is out of range"))?;
            let p = front[at] as usize;
            if got[p] != 0 {
                // The second child: its side is implied (and sent as 0).
                if right {
                    return Err(bad("a second child's side is not implied"));
                }
                right = got[p] == 1;
            }
            let bit = 1u8 << u8::from(right);
            if got[p] & bit != 0 {
                return Err(bad("a node gets the same child twice"));
            }
            got[p] |= bit;
            if got[p] == 3 {
                sibling = Some((words[p][6 + usize::from(!right)] - first) as usize);
            }
            words[p][6 + usize::from(right)] = g;
            if got[p] == 3 {
                front.remove(at);
            }
            root_of[l] = root_of[p];
            if words[p][0] & INCOMPLETE == 0 {
                complete_parent = Some(qbox_of(&words[p]));
            }
        }
        if g != 0 {
            let mut rs = [0u32; 6];
            let sib = sibling.map(|x| u32::from(nonzero_of[x]));
            let has_sib = sib.is_some();
            let mut zero = dec[mask_context(leaf, right, has_sib)].decode(&mut rmask)?;
            if zero >= 64 {
                return Err(bad("a zero mask is out of range"));
            }
            zero ^= sib.unwrap_or(0);
            // Each component comes from a stream of its own: six
            // independent dependency chains for the processor to overlap.
            let maxb = h.bits + 2;
            // Only the components the mask marks non-zero are coded.
            let mut nonzero = !zero & 63;
            while nonzero != 0 {
                let k = nonzero.trailing_zeros() as usize;
                nonzero &= nonzero - 1;
                rs[k] = dec[value_context(leaf, right, k, has_sib)]
                    .decode_bucketed(&mut rres[k], maxb)?;
            }
            let got_nonzero = rs
                .iter()
                .enumerate()
                .fold(0u32, |m, (k, &v)| m | u32::from(v != 0) << k);
            if got_nonzero != !zero & 63 {
                return Err(bad("a residual marked non-zero is zero"));
            }
            nonzero_of[l] = got_nonzero as u8;
            let res = rs;
            match complete_parent {
                Some(pq) => {
                    let q = apply(&pq, right, &res, h.grid.max_q)
                        .ok_or_else(|| bad("a decoded box leaves the grid"))?;
                    words[l][..3].copy_from_slice(&q.min.to_array());
                    words[l][3..6].copy_from_slice(&q.max.to_array());
                }
                None => {
                    words[l][..6].copy_from_slice(&res);
                    words[l][0] |= INCOMPLETE;
                }
            }
        }
        if leaf {
            let count = if h.empty {
                0
            } else if h.max_leaf > 1 {
                dec[CTX_COUNT].decode(&mut r)?
            } else {
                1
            };
            if count > h.max_leaf || (count == 0 && !h.empty) {
                return Err(bad("a leaf has a bad triangle count"));
            }
            if let Some(x) = sibling.filter(|&x| words[x][7] == LEAF_FLAG | 1) {
                last_tri = i64::from(words[x][6]);
            }
            let slot = tris.len() as u32;
            for _ in 0..count {
                let s = dec[CTX_TRI].decode(&mut r)?;
                let id = if s == 0 {
                    let b = dec[CTX_TRI_FAR].decode(&mut r)?;
                    if b > 33 {
                        return Err(bad("a triangle-id delta is too long"));
                    }
                    let z = if b <= 1 {
                        u64::from(b)
                    } else {
                        (1u64 << (b - 1)) | r.get(b - 1)
                    };
                    last_tri + unzigzag(z)
                } else {
                    last_tri + unzigzag(u64::from(s - 1))
                };
                if id < 0 || id >= i64::from(h.triangle_count) {
                    return Err(bad("a triangle id is out of range"));
                }
                last_tri = id;
                if count > 1 {
                    tris.push(id as u32);
                } else {
                    words[l][6] = id as u32;
                }
            }
            if count != 1 {
                words[l][6] = slot;
            }
            words[l][7] = LEAF_FLAG | count;
        } else {
            front.push(l as u32);
        }
    }
    let mut last_child = i64::from(end);
    for &f in &front {
        for side in 0..2 {
            if got[f as usize] & (1 << side) == 0 {
                let child = last_child + unzigzag(u64::from(dec[CTX_CHILD].decode(&mut r)?));
                if child < i64::from(end) || child >= i64::from(h.node_count) {
                    return Err(bad("a local leaf's child is out of range"));
                }
                words[f as usize][6 + side] = child as u32;
                last_child = child;
            }
        }
    }
    if r.overran() || rmask.overran() || rres.iter().any(|x| x.overran()) {
        return Err(bad("the cluster's bits run past its end"));
    }
    let bytes = n_us * 32 + n_us * 2 + tris.len() * 4 + roots.len() * 12 + 128;
    Ok(Cluster {
        first,
        nodes: words.into_iter().map(CoreNode::new).collect(),
        tris: tris.into_boxed_slice(),
        roots: roots.into_boxed_slice(),
        root_of: root_of.into_boxed_slice(),
        lock: Mutex::new(()),
        live: live.token(bytes),
    })
}

impl RacBvh {
    /// Decompresses cluster `c` without touching the cache (for throughput
    /// measurements and [`verify`](Self::verify)). Returns its node count.
    pub fn decode_cluster_uncached(&self, c: u32) -> Result<usize, RacError> {
        Ok(self.decode(c)?.nodes.len())
    }

    /// What the whole tree decodes to, in the cache's measure: the bytes of
    /// every cluster, each decoded once without touching the cache, so the
    /// figure does not depend on the cache's budget.
    pub fn decoded_bytes(&self) -> Result<usize, RacError> {
        let mut total = 0;
        for c in 0..self.meta.len() as u32 {
            total += Page::bytes(&self.decode(c)?);
        }
        Ok(total)
    }

    fn decode(&self, c: u32) -> Result<Cluster, RacError> {
        let m = self.meta.get(c as usize).ok_or(RacError::CorruptCluster {
            cluster: c,
            what: "no such cluster",
        })?;
        let end = self
            .meta
            .get(c as usize + 1)
            .map_or(self.data.len() as u64, |n| n.offset);
        let bytes =
            self.data
                .get(m.offset as usize..end as usize)
                .ok_or(RacError::CorruptCluster {
                    cluster: c,
                    what: "its byte range is out of bounds",
                })?;
        if xxhash_rust::xxh3::xxh3_64(bytes) != m.hash {
            return Err(RacError::CorruptCluster {
                cluster: c,
                what: "its checksum does not match",
            });
        }
        decode_cluster(
            &self.header,
            c,
            c << self.header.cluster_bits,
            m.nodes,
            bytes,
            self.cache.live(),
        )
        .map_err(|e| match e {
            // The bit and dictionary coders do not know where they are.
            RacError::Format(FormatError::Corrupt { what }) => {
                RacError::CorruptCluster { cluster: c, what }
            }
            e => e,
        })
    }

    /// Cluster `c`, from the cache or decompressed into it.
    pub(super) fn cluster(&self, c: u32) -> Result<Arc<Cluster>, RacError> {
        self.cache.get_or_decode(c, || self.decode(c))
    }
}
