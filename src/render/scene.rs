//! Scenes: instances (a [`RayTarget`] placed with a [`Pose`], a material
//! and optional smooth vertex normals), and the scene-level ray queries.

use glam::Vec3A;

use super::target::RayTarget;
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Pose, Ray};
use crate::mesh::Mesh;
use crate::query::packet::MAX_PACKET;
use crate::query::ray::RayHit;

/// Area-weighted per-vertex normals of a mesh, computed once.
///
/// Each vertex gets the sum of the (unnormalised, hence area-weighted)
/// normals of its triangles, normalised. A vertex whose sum vanishes (no
/// triangles, only degenerate ones, or opposite faces cancelling) has no
/// normal, and triangles touching it are shaded with their face normal.
#[derive(Clone, Debug, Default)]
pub struct VertexNormals {
    normals: Vec<[f32; 3]>,
}

impl VertexNormals {
    /// The normals of `mesh`'s vertices. Triangle indices must be valid.
    pub fn from_mesh(mesh: &Mesh) -> Self {
        let mut acc = vec![Vec3A::ZERO; mesh.vertices.len()];
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| Vec3A::from(mesh.vertices[i as usize]));
            let n = (b - a).cross(c - a);
            if n.is_finite() {
                for &i in t {
                    acc[i as usize] += n;
                }
            }
        }
        let normals = acc
            .into_iter()
            .map(|n| {
                let len = n.length();
                if len > 0.0 && len.is_finite() {
                    (n / len).to_array()
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        Self { normals }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.normals.len()
    }

    /// Whether there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.normals.is_empty()
    }

    /// The unit normal of vertex `i`, `None` if it is degenerate or out of range.
    #[inline]
    pub fn get(&self, i: u32) -> Option<Vec3A> {
        let n = Vec3A::from(*self.normals.get(i as usize)?);
        (n != Vec3A::ZERO).then_some(n)
    }
}

/// Surface appearance (linear RGB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Diffuse (Lambert) colour.
    pub color: Vec3A,
    /// Phong specular weight.
    pub specular: f32,
    /// Phong exponent.
    pub shininess: f32,
    /// Mirror reflectivity in `[0, 1]`.
    pub reflectivity: f32,
}

impl Material {
    /// Default materials given to instances in turn.
    pub const PALETTE: [Material; 4] = [
        Material::new([0.62, 0.56, 0.48], 0.3, 40.0, 0.06),
        Material::new([0.55, 0.32, 0.22], 0.4, 60.0, 0.08),
        Material::new([0.32, 0.45, 0.62], 0.4, 60.0, 0.08),
        Material::new([0.42, 0.58, 0.36], 0.3, 30.0, 0.05),
    ];

    /// A material from a linear colour and Phong/mirror weights.
    pub const fn new(color: [f32; 3], specular: f32, shininess: f32, reflectivity: f32) -> Self {
        Self {
            color: Vec3A::new(color[0], color[1], color[2]),
            specular,
            shininess,
            reflectivity,
        }
    }
}

/// One placed object of a [`Scene`].
#[derive(Clone, Copy)]
pub struct Instance<'a> {
    /// The structure rays are shot at, in its local coordinates.
    pub target: &'a dyn RayTarget,
    /// Local to world.
    pub pose: Pose,
    /// Smooth normals by vertex index, used when the target exposes
    /// [`RayTarget::vertex_indices`]; `None` shades with face normals.
    pub normals: Option<&'a VertexNormals>,
    /// Appearance.
    pub material: Material,
}

impl<'a> Instance<'a> {
    /// An instance with the first palette material.
    pub fn new(target: &'a dyn RayTarget, pose: Pose, normals: Option<&'a VertexNormals>) -> Self {
        Self {
            target,
            pose,
            normals,
            material: Material::PALETTE[0],
        }
    }
}

/// Keeps instance `instance`'s hit `h` if it is nearer than `best` (or the
/// first), updating `best_t`: the one rule of [`Scene::closest`] and
/// [`Scene::closest_packet`].
#[inline]
fn keep_nearer(best: &mut Option<SceneHit>, best_t: &mut f32, instance: usize, h: RayHit) {
    if h.t < *best_t || best.is_none() {
        *best_t = h.t;
        *best = Some(SceneHit { instance, hit: h });
    }
}

/// The closest hit in a scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneHit {
    /// Which instance was hit.
    pub instance: usize,
    /// The hit in the instance's local coordinates (`t` is the same in
    /// world coordinates: poses are rigid).
    pub hit: RayHit,
}

/// What shading needs at a hit point (world coordinates).
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// The hit point.
    pub point: Vec3A,
    /// Unit face normal, turned to face the incoming ray.
    pub geometric: Vec3A,
    /// Unit shading normal (smooth where possible), on the same side.
    pub shading: Vec3A,
    /// Appearance.
    pub material: Material,
}

/// Several instances. A single mesh is a scene of one.
pub struct Scene<'a> {
    instances: Vec<Instance<'a>>,
    inverse: Vec<Pose>,
    boxes: Vec<Aabb>,
    bounds: Aabb,
}

impl<'a> Scene<'a> {
    /// A scene of `instances`.
    pub fn new(instances: Vec<Instance<'a>>) -> Self {
        let inverse = instances.iter().map(|i| i.pose.inverse()).collect();
        let boxes: Vec<Aabb> = instances
            .iter()
            .map(|i| {
                let b = i.target.bounds();
                if b.is_empty() {
                    b
                } else {
                    b.transformed(&i.pose)
                }
            })
            .collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
        Self {
            instances,
            inverse,
            boxes,
            bounds,
        }
    }

    /// One target at the identity pose.
    pub fn single(target: &'a dyn RayTarget, normals: Option<&'a VertexNormals>) -> Self {
        Self::new(vec![Instance::new(target, Pose::IDENTITY, normals)])
    }

    /// The instances.
    pub fn instances(&self) -> &[Instance<'a>] {
        &self.instances
    }

    /// World box of all instances (empty for an empty scene).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    #[inline]
    fn local_ray(&self, i: usize, ray: &Ray) -> Ray {
        let inv = &self.inverse[i];
        if self.instances[i].pose == Pose::IDENTITY {
            *ray
        } else {
            Ray::new(
                inv.transform_point(ray.origin),
                inv.transform_vector(ray.dir),
            )
        }
    }

    /// The closest hit within `[0, t_max]` over all instances.
    pub fn closest(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<SceneHit> {
        let mut best: Option<SceneHit> = None;
        let mut best_t = t_max;
        for (i, inst) in self.instances.iter().enumerate() {
            if ray.intersect_aabb(&self.boxes[i], best_t).is_none() {
                continue;
            }
            let local = self.local_ray(i, ray);
            if let Some(h) = inst.target.closest(&local, best_t, stats) {
                keep_nearer(&mut best, &mut best_t, i, h);
            }
        }
        best
    }

    /// [`Scene::closest`] for a packet of up to [`MAX_PACKET`] coherent rays
    /// (within `[0, ∞)`), each instance traversed once for the rays that
    /// meet its box: the same hits, ray by ray.
    pub fn closest_packet(
        &self,
        rays: &[Ray],
        out: &mut [Option<SceneHit>],
        stats: &mut TraversalStats,
    ) {
        let n = rays.len();
        assert!(
            n <= MAX_PACKET && out.len() == n,
            "a packet of at most {MAX_PACKET} rays"
        );
        out.fill(None);
        let mut best_t = [f32::INFINITY; MAX_PACKET];
        let mut local = [Ray::new(Vec3A::ZERO, Vec3A::Z); MAX_PACKET];
        let mut limit = [0.0f32; MAX_PACKET];
        let mut which = [0usize; MAX_PACKET];
        let mut hits = [None; MAX_PACKET];
        for (i, inst) in self.instances.iter().enumerate() {
            let mut k = 0;
            for (r, ray) in rays.iter().enumerate() {
                if ray.intersect_aabb(&self.boxes[i], best_t[r]).is_some() {
                    local[k] = self.local_ray(i, ray);
                    limit[k] = best_t[r];
                    which[k] = r;
                    k += 1;
                }
            }
            if k == 0 {
                continue;
            }
            inst.target
                .closest_packet(&local[..k], &limit[..k], &mut hits[..k], stats);
            for (&r, h) in which[..k].iter().zip(&hits[..k]) {
                if let Some(h) = h {
                    keep_nearer(&mut out[r], &mut best_t[r], i, *h);
                }
            }
        }
    }

    /// Whether anything is hit within `[0, t_max]`.
    pub fn any(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
        self.instances.iter().enumerate().any(|(i, inst)| {
            ray.intersect_aabb(&self.boxes[i], t_max).is_some()
                && inst.target.any(&self.local_ray(i, ray), t_max, stats)
        })
    }

    /// The shading frame of `hit` for `ray`.
    pub fn surface(&self, ray: &Ray, hit: &SceneHit) -> Surface {
        let inst = &self.instances[hit.instance];
        let h = &hit.hit;
        let tri = inst.target.triangle(h.triangle);
        let face = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
        let smooth = inst.normals.and_then(|normals| {
            let idx = inst.target.vertex_indices(h.triangle)?;
            let [a, b, c] = [
                normals.get(idx[0])?,
                normals.get(idx[1])?,
                normals.get(idx[2])?,
            ];
            let n = a * (1.0 - h.u - h.v) + b * h.u + c * h.v;
            let n = n.normalize_or_zero();
            (n != Vec3A::ZERO).then_some(n)
        });
        let pose = &inst.pose;
        let mut geometric = pose.transform_vector(face);
        if geometric == Vec3A::ZERO {
            geometric = -ray.dir.normalize_or_zero();
        }
        let mut shading = smooth
            .map(|n| pose.transform_vector(n))
            .unwrap_or(geometric);
        if geometric.dot(ray.dir) > 0.0 {
            geometric = -geometric;
        }
        if shading.dot(geometric) < 0.0 {
            shading = -shading;
        }
        Surface {
            point: ray.at(h.t),
            geometric,
            shading,
            material: inst.material,
        }
    }
}
