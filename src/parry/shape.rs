//! [`CbvhShape`]: one parry shape type over any cbvh codec.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use glam::{Mat3A, Vec3A};
use parry3d::bounding_volume::{Aabb as PAabb, BoundingSphere};
use parry3d::mass_properties::MassProperties;
use parry3d::math::{Pose as PPose, Real, Vector};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::details::NormalConstraints;
use parry3d::query::{
    PointProjection, PointQuery, PointQueryWithLocation, Ray as PRay, RayCast, RayIntersection,
};
use parry3d::shape::{
    CompositeShape, FeatureId, Shape, ShapeType, Triangle as PTriangle, TrianglePointLocation,
    TrianglePseudoNormals, TypedCompositeShape, TypedShape,
};

use crate::build::{BuildError, BuildOptions, build};
use crate::codec::common::MassProps;
use crate::codec::{
    AnyCodec, AnyOptions, ByteSize, CodecError, CodecFileError, CodecKind, OpenOptions,
};
use crate::contact::edges::{BACK, FRONT};
use crate::contact::{EdgeFlags, Facing};
use crate::cursor::{NodeCursor, Scaled, TraversalStats};
use crate::geom::{Aabb, Pose, Ray, TriHit, Triangle};
use crate::mesh::Mesh;
use crate::query;
use crate::with_codec;

/// What can go wrong building a [`CbvhShape`] from a mesh.
#[derive(Debug, thiserror::Error)]
pub enum ShapeBuildError {
    /// The tree could not be built over the mesh.
    #[error("building the tree: {0}")]
    Build(#[from] BuildError),
    /// The codec could not encode the tree.
    #[error("encoding the {codec} codec: {source}")]
    Encode {
        /// The codec.
        codec: CodecKind,
        /// The codec's error.
        #[source]
        source: CodecError,
    },
}

struct Inner {
    codec: AnyCodec,
    triangles: usize,
}

/// What depends on the shape's scale ([`CbvhShape::scaled`]): shared by
/// the clones of one view, made anew for each scale.
struct View {
    /// The factors the codec's tree is scaled by (all 1 unscaled).
    scale: Vec3A,
    /// Active edges, by triangle id ([`EdgeFlags`]): the codec's (shared,
    /// not copied) or the ones given to [`CbvhShape::with_edges`], for the
    /// scale.
    edges: EdgeFlags,
    aabb: Aabb,
    /// Mass properties at density 1.
    unit_mass: MassProperties,
    fallback: OnceLock<Bvh>,
    fallback_builds: AtomicUsize,
    /// [`CbvhShape::ccd_thickness`], computed on first use (it walks every
    /// triangle).
    thickness: OnceLock<Real>,
}

impl View {
    fn new(scale: Vec3A, edges: EdgeFlags, aabb: Aabb, unit_mass: MassProperties) -> Arc<Self> {
        Arc::new(View {
            scale,
            edges,
            aabb,
            unit_mass,
            fallback: OnceLock::new(),
            fallback_builds: AtomicUsize::new(0),
            thickness: OnceLock::new(),
        })
    }
}

/// A triangle mesh stored as a cbvh BVH, usable as a parry / rapier shape.
///
/// Cloning is cheap: the data sits behind an `Arc`. Install
/// [`Dispatcher`](super::Dispatcher) in rapier's narrow phase so that contacts
/// run on the cbvh tree; without it, parry's composite-shape code still works
/// through [`CompositeShape::bvh`], which builds a parry `Bvh` on first use
/// (the compatibility fallback, see [`CbvhShape::fallback_bvh_built`]).
#[derive(Clone)]
pub struct CbvhShape {
    inner: Arc<Inner>,
    view: Arc<View>,
    sides: Sides,
}

/// Which side of its triangles a [`CbvhShape`] takes contacts on (see
/// [`crate::contact::orient`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sides {
    /// A closed mesh is one-sided (outward, whichever way it is wound); an
    /// open one (a ground, a ramp, a bowl) two-sided: each triangle faces
    /// the other shape's centre. The default.
    #[default]
    Auto,
    /// Contacts only on the side the winding's normals point to (for an
    /// open mesh whose back must never be touched, or whose other shapes
    /// may have their centre behind it, like a terrain under a long body).
    OneSided,
    /// Each triangle faces the other shape's centre, even on a closed mesh.
    TwoSided,
}

impl std::fmt::Debug for CbvhShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CbvhShape")
            .field("codec", &self.inner.codec.name())
            .field("triangles", &self.inner.triangles)
            .field("fallback_bvh_built", &self.fallback_bvh_built())
            .finish()
    }
}

/// parry's mass properties from the stored ones (parry's own
/// `with_inertia_matrix`, as its `from_trimesh` ends).
pub fn parry_mass(m: &MassProps) -> MassProperties {
    if m.mass == 0.0 {
        return MassProperties::default();
    }
    MassProperties::with_inertia_matrix(
        Vector::from_array(m.com),
        m.mass,
        parry3d::math::Matrix::from_cols_array(&m.inertia),
    )
}

/// `m` for the body scaled by `s` along its local axes: the mass by
/// `|det S|`, the centre of mass by `S`, and the inertia tensor about the
/// centre of mass through the second moments `C = tr(I)/2 E - I`, which
/// scale as `|det S| S C S` (so `I' = tr(C') E - C'`).
fn scaled_mass(m: &MassProperties, s: Vec3A) -> MassProperties {
    if m.inv_mass == 0.0 {
        return *m;
    }
    let det = (s.x * s.y * s.z).abs();
    let i = m.reconstruct_inertia_matrix();
    let trace = i.x_axis.x + i.y_axis.y + i.z_axis.z;
    let c = parry3d::math::Matrix::from_diagonal(Vector::splat(0.5 * trace)) - i;
    let sm = parry3d::math::Matrix::from_diagonal(s.into());
    let c2 = sm * c * sm * det;
    let trace2 = c2.x_axis.x + c2.y_axis.y + c2.z_axis.z;
    let i2 = parry3d::math::Matrix::from_diagonal(Vector::splat(trace2)) - c2;
    MassProperties::with_inertia_matrix(m.local_com * Vector::from(s), m.mass() * det, i2)
}

/// Converts a parry pose into cbvh's.
#[inline]
pub fn pose_from_parry(p: &PPose) -> Pose {
    Pose {
        rotation: Mat3A::from_quat(p.rotation),
        translation: Vec3A::from(p.translation),
    }
}

#[inline]
pub(crate) fn to_parry_triangle(t: &Triangle) -> PTriangle {
    PTriangle::new(t[0].into(), t[1].into(), t[2].into())
}

#[inline]
pub(crate) fn to_parry_aabb(b: &Aabb) -> PAabb {
    PAabb::new(b.min.into(), b.max.into())
}

#[inline]
pub(crate) fn from_parry_aabb(b: &PAabb) -> Aabb {
    Aabb::new(b.mins.into(), b.maxs.into())
}

impl CbvhShape {
    /// Builds the tree over `mesh` with `options`, then encodes it with the
    /// codec `kind` and its options in `codec_options`.
    pub fn build(
        mesh: &Mesh,
        options: &BuildOptions,
        kind: CodecKind,
        codec_options: &AnyOptions,
    ) -> Result<Self, ShapeBuildError> {
        let bvh = build(mesh, options, &|_, _| {})?;
        let codec = AnyCodec::encode(kind, &bvh, mesh, codec_options).map_err(|source| {
            ShapeBuildError::Encode {
                codec: kind,
                source,
            }
        })?;
        Ok(Self::new(codec))
    }

    /// [`CbvhShape::build`] with the plain codec (the uncompressed
    /// reference, which has no options).
    pub fn plain(mesh: &Mesh, options: &BuildOptions) -> Result<Self, ShapeBuildError> {
        Self::build(mesh, options, CodecKind::Plain, &AnyOptions::default())
    }

    /// Wraps an already encoded codec built from `mesh`. The codec carries
    /// its own mass properties, so the mesh is only checked against it (a
    /// warning is logged if the triangle counts differ); prefer
    /// [`CbvhShape::new`].
    pub fn from_codec(codec: AnyCodec, mesh: &Mesh) -> Self {
        if mesh.triangles.len() != codec.triangle_count() {
            log::warn!(
                "cbvh: from_codec was given a mesh of {} triangles for a codec of {}; \
                 the codec's own triangles and mass properties are used",
                mesh.triangles.len(),
                codec.triangle_count()
            );
        }
        Self::new(codec)
    }

    /// Opens any cbvh codec file (chosen by its magic) as a shape, verified
    /// (see [`AnyCodec::open`]). No mesh is needed: the file holds the mass
    /// properties.
    pub fn open(path: &std::path::Path) -> Result<Self, CodecFileError> {
        Ok(Self::new(AnyCodec::open(path, &OpenOptions::default())?))
    }

    /// Wraps an encoded codec (built, or opened from its file), with the
    /// mass properties and the active edges it stores
    /// ([`AnyCodec::edge_flags`]: computed when it was encoded from its
    /// triangles as it holds them, its ids and its vertex precision, and
    /// read from its file when opened; nothing is computed here).
    pub fn new(codec: AnyCodec) -> Self {
        let edges = codec.edge_flags().clone();
        Self::with_edges(codec, edges)
    }

    /// Wraps an encoded codec with other edge flags than the ones it
    /// stores (computed from the same triangles with another flat angle,
    /// say; ids as the codec's).
    pub fn with_edges(codec: AnyCodec, edges: EdgeFlags) -> Self {
        let unit_mass = parry_mass(&codec.mass());
        let aabb = with_codec!(&codec, |c| c.root().1);
        Self {
            inner: Arc::new(Inner {
                triangles: codec.triangle_count(),
                codec,
            }),
            view: View::new(Vec3A::ONE, edges, aabb, unit_mass),
            sides: Sides::Auto,
        }
    }

    /// The same shape scaled by `scale` along its local axes: a view over
    /// the same compressed tree, not a re-encoding ([`Scaled`]). Uniform,
    /// non-uniform and mirrored (negative) factors are taken; a scaled
    /// shape scales again by the product. `None` if a factor is zero or
    /// not finite.
    ///
    /// Every query of the view answers as a shape built from the mesh with
    /// its vertices scaled first: boxes, triangles (and so contacts, rays,
    /// casts and projections), the mass properties (mass by `|sx sy sz|`,
    /// the centre of mass by `scale`, the inertia tensor from the scaled
    /// second moments) and the active edges. A uniform factor keeps every
    /// angle, so the edge flags are shared; a mirror turns the surface's
    /// sides about (the front and back bits swap, and a closed mesh's
    /// outward side with them); a non-uniform scale changes the angles
    /// between triangles, so the flags are computed again from the scaled
    /// triangles, at the default flat angle (about a second a million
    /// triangles, one byte a triangle kept).
    pub fn scaled(&self, scale: Vector) -> Option<CbvhShape> {
        let total = self.view.scale * Vec3A::from(scale);
        if !total.is_finite() || total.cmpeq(Vec3A::ZERO).any() {
            return None;
        }
        let s = Vec3A::from(scale);
        let det = f64::from(s.x) * f64::from(s.y) * f64::from(s.z);
        let uniform = s.x.abs() == s.y.abs() && s.y.abs() == s.z.abs();
        let edges = if uniform {
            let e = &self.view.edges;
            let mut out = if det < 0.0 {
                let swapped = e
                    .as_slice()
                    .iter()
                    .map(|&f| ((f & FRONT) << 3) | ((f & BACK) >> 3))
                    .collect();
                let mut m = EdgeFlags::from_flags(swapped).expect("swapped flags stay in range");
                m.boundary_edges = e.boundary_edges;
                m.non_manifold_edges = e.non_manifold_edges;
                m.misoriented_edges = e.misoriented_edges;
                m.flat_edges = e.flat_edges;
                m
            } else {
                e.clone()
            };
            out.signed_volume = e.signed_volume * det;
            out
        } else {
            with_codec!(&self.inner.codec, |raw| {
                let c = Scaled::new(raw, total);
                EdgeFlags::compute(c.triangle_count(), |id| c.triangle(id))
            })
        };
        let aabb = self.view.aabb.scaled(s);
        let unit_mass = scaled_mass(&self.view.unit_mass, s);
        Some(CbvhShape {
            inner: self.inner.clone(),
            view: View::new(total, edges, aabb, unit_mass),
            sides: self.sides,
        })
    }

    /// The factors the codec's tree is scaled by along each local axis
    /// (all 1 for a shape that was never [`scaled`](Self::scaled)).
    pub fn scale(&self) -> Vec3A {
        self.view.scale
    }

    /// The thickness rapier's continuous collision detection takes for
    /// the shape ([`Shape::ccd_thickness`]): rapier sweeps a body whose
    /// points move more than half its colliders' least thickness in a step
    /// (in rapier 0.36 every dynamic body, `ccd_enabled` or not), and
    /// otherwise trusts its discrete contacts.
    ///
    /// - A closed mesh: three times its volume over its surface area, which
    ///   is parry's own value for its ball (the radius) and its cuboid (the
    ///   least half extent) and, for any convex body, at most three times
    ///   the radius of the largest ball inside it (volume over area never
    ///   exceeds that radius): half of it is less than the body's least
    ///   width, so a body rapier leaves unswept cannot cross a surface of
    ///   zero thickness in one step. A slab of thickness `t` gives `1.5 t`.
    ///   A non-convex body's thin parts (a statue's fingers) can be thinner
    ///   than this average.
    /// - An open mesh (a surface, a sheet, a terrain piece): infinite: such
    ///   a body is never swept and relies on its speculative contacts. Its
    ///   real thickness is zero, and a zero here (parry's `TriMesh` answers
    ///   0) sweeps it on every step it moves, resting or not.
    ///
    /// As a sweep's *target* (a fast body against a cbvh wall, floor or
    /// level, closed or open), rapier calls the dispatcher's nonlinear
    /// cast whatever this value is, and a zero-thickness wall stops it.
    ///
    /// Computed on first call (rapier calls it when the collider is
    /// attached to a body) by one walk over the triangles, then kept.
    pub fn ccd_thickness(&self) -> Real {
        *self.view.thickness.get_or_init(|| {
            let volume = self.view.edges.signed_volume.abs();
            if !self.view.edges.is_closed() || volume <= 0.0 {
                return Real::MAX;
            }
            let mut area = 0.0f64;
            let mut stats = TraversalStats::default();
            with_cursor!(self, |c| crate::query::visit(
                c,
                &mut stats,
                |_| true,
                |_, t| {
                    let n = (t[1] - t[0]).cross(t[2] - t[0]);
                    area += 0.5 * f64::from(n.length());
                    std::ops::ControlFlow::Continue(())
                }
            ));
            if area > 0.0 {
                (3.0 * volume / area) as Real
            } else {
                Real::MAX
            }
        })
    }

    /// The same shape taking contacts on `sides` (cheap: the data is
    /// shared).
    pub fn with_sides(mut self, sides: Sides) -> Self {
        self.sides = sides;
        self
    }

    /// Which sides the shape takes contacts on.
    pub fn sides(&self) -> Sides {
        self.sides
    }

    /// The active edges of the triangles, by id: the codec's, or the ones
    /// given to [`with_edges`](Self::with_edges).
    pub fn edge_flags(&self) -> &EdgeFlags {
        &self.view.edges
    }

    /// The edge flags of triangle `id` ([`EdgeFlags::get`]).
    #[inline]
    pub fn edge_flags_of(&self, id: u32) -> u8 {
        self.view.edges.get(id)
    }

    /// How the triangles face a contact with a shape whose centre is at
    /// `toward` (in the frame the triangles are given in): one-sided
    /// outward for a closed mesh, two-sided toward `toward` for an open one
    /// (with [`Sides::Auto`]).
    pub fn facing(&self, toward: Vec3A) -> Facing {
        match self.sides {
            Sides::Auto if self.view.edges.is_closed() => {
                Facing::OneSided(self.view.edges.outward())
            }
            Sides::OneSided => Facing::OneSided(1.0),
            _ => Facing::TwoSided { toward },
        }
    }

    /// The codec inside.
    pub fn codec(&self) -> &AnyCodec {
        &self.inner.codec
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.inner.triangles
    }

    /// Memory of the codec in bytes (all parts).
    pub fn bytes_total(&self) -> usize {
        self.inner.codec.bytes_total()
    }

    /// The local box, as cbvh's type.
    pub fn local_aabb(&self) -> Aabb {
        self.view.aabb
    }

    /// Whether the compatibility fallback (a parry `Bvh`) has been built.
    /// The native path, through [`Dispatcher`](super::Dispatcher), never builds it.
    pub fn fallback_bvh_built(&self) -> bool {
        self.view.fallback.get().is_some()
    }

    /// How many times a caller asked for the fallback `Bvh` (each call of
    /// [`CompositeShape::bvh`]).
    pub fn fallback_bvh_requests(&self) -> usize {
        self.view.fallback_builds.load(Ordering::Relaxed)
    }

    /// Triangle `id` as a parry triangle.
    pub fn parry_triangle(&self, id: u32) -> PTriangle {
        with_cursor!(self, |c| to_parry_triangle(&c.triangle(id)))
    }
}

impl RayCast for CbvhShape {
    fn cast_local_ray_and_get_normal(
        &self,
        ray: &PRay,
        max_time_of_impact: Real,
        solid: bool,
    ) -> Option<RayIntersection> {
        let r = Ray::new(ray.origin.into(), ray.dir.into());
        let mut stats = TraversalStats::default();
        let mut best: Option<RayIntersection> = None;
        // The primitive test is parry's own triangle ray cast, so hits,
        // normals and features are exactly parry's TriMesh's.
        with_cursor!(self, |c| query::closest_hit_with(
            c,
            &r,
            max_time_of_impact,
            &mut stats,
            |id, tri, t_max| {
                let hit =
                    to_parry_triangle(tri).cast_local_ray_and_get_normal(ray, t_max, solid)?;
                if best.is_none_or(|b| hit.time_of_impact < b.time_of_impact) {
                    best = Some(hit.with_subshape(id));
                }
                Some(TriHit {
                    t: hit.time_of_impact,
                    u: 0.0,
                    v: 0.0,
                })
            }
        ));
        best
    }
}

impl CbvhShape {
    /// The triangle closest to `pt` (ties to the lower id), found on the
    /// cbvh tree, with its id.
    fn closest_triangle(&self, pt: Vector) -> Option<(u32, PTriangle)> {
        let mut stats = TraversalStats::default();
        let hit = with_cursor!(self, |c| query::closest_point(
            c,
            pt.into(),
            f32::INFINITY,
            &mut stats
        ))?;
        Some((hit.triangle, self.parry_triangle(hit.triangle)))
    }
}

/// The feature of a triangle a point projects on, as parry's `TriMesh`
/// reports it (parry's own mapping is private).
fn triangle_feature(location: TrianglePointLocation) -> FeatureId {
    match location {
        TrianglePointLocation::OnVertex(i) => FeatureId::Vertex(i),
        TrianglePointLocation::OnEdge(i, _) => FeatureId::Edge(i),
        TrianglePointLocation::OnFace(i, _) => FeatureId::Face(i),
        TrianglePointLocation::OnSolid => FeatureId::Face(0),
    }
}

/// Projections answer as parry's `TriMesh` (without pseudo-normals) does:
/// the closest triangle is found on the cbvh tree, then projected on with
/// parry's own triangle code, so the point, `is_inside` (true only for a
/// point on the surface: a triangle mesh is a surface) and the feature (the
/// triangle's own vertex, edge or face) are parry's, and
/// `PointProjection::subshape` names the triangle.
impl PointQuery for CbvhShape {
    fn project_local_point(&self, pt: Vector, solid: bool) -> PointProjection {
        match self.closest_triangle(pt) {
            Some((id, tri)) => tri.project_local_point(pt, solid).with_subshape(id),
            None => PointProjection::new(false, pt),
        }
    }

    fn project_local_point_and_get_feature(&self, pt: Vector) -> (PointProjection, FeatureId) {
        match self.closest_triangle(pt) {
            Some((id, tri)) => {
                let (proj, location) = tri.project_local_point_and_get_location(pt, false);
                (proj.with_subshape(id), triangle_feature(location))
            }
            None => (PointProjection::new(false, pt), FeatureId::Unknown),
        }
    }
}

impl Shape for CbvhShape {
    fn compute_local_aabb(&self) -> PAabb {
        to_parry_aabb(&self.view.aabb)
    }

    fn compute_local_bounding_sphere(&self) -> BoundingSphere {
        let b = self.view.aabb;
        BoundingSphere::new(b.center().into(), b.half_extents().length())
    }

    fn clone_dyn(&self) -> Box<dyn Shape> {
        Box::new(self.clone())
    }

    /// A scaled view over the same compressed tree ([`CbvhShape::scaled`]);
    /// `None` for a zero or non-finite factor. A mesh needs no
    /// subdivisions: its triangles scale exactly.
    fn scale_dyn(&self, scale: Vector, _num_subdivisions: u32) -> Option<Box<dyn Shape>> {
        Some(Box::new(self.scaled(scale)?))
    }

    fn mass_properties(&self, density: Real) -> MassProperties {
        let m = self.view.unit_mass;
        if m.inv_mass == 0.0 {
            return m;
        }
        MassProperties {
            inv_mass: m.inv_mass / density,
            inv_principal_inertia: m.inv_principal_inertia / density,
            ..m
        }
    }

    fn shape_type(&self) -> ShapeType {
        ShapeType::Custom
    }

    fn as_typed_shape(&self) -> TypedShape<'_> {
        TypedShape::Custom(self)
    }

    /// See [`CbvhShape::ccd_thickness`].
    fn ccd_thickness(&self) -> Real {
        CbvhShape::ccd_thickness(self)
    }

    /// A quarter turn at most between contacts that differ, parry's value
    /// for its own meshes (rapier's sweeps step rotations by π minus it).
    fn ccd_angular_thickness(&self) -> Real {
        std::f32::consts::FRAC_PI_4
    }

    fn as_composite_shape(&self) -> Option<&(dyn CompositeShape + Sync)> {
        Some(self)
    }
}

impl CompositeShape for CbvhShape {
    fn map_part_at(
        &self,
        shape_id: u32,
        f: &mut dyn FnMut(Option<&PPose>, &dyn Shape, Option<&dyn NormalConstraints>),
    ) {
        let tri = self.parry_triangle(shape_id);
        f(None, &tri, None)
    }

    /// The compatibility fallback: builds a parry `Bvh` over the triangles on
    /// first call (logged once). The cbvh dispatcher never calls this. Set
    /// `CBVH_DEBUG_FALLBACK=1` to print a backtrace of the caller.
    fn bvh(&self) -> &Bvh {
        self.view.fallback_builds.fetch_add(1, Ordering::Relaxed);
        self.view.fallback.get_or_init(|| {
            if std::env::var_os("CBVH_DEBUG_FALLBACK").is_some() {
                log::warn!("{}", std::backtrace::Backtrace::force_capture());
            }
            log::warn!(
                "cbvh: building a parry Bvh over {} triangles for a {} shape: a query reached \
                 parry's composite-shape code. Install cbvh::parry::Dispatcher \
                 (NarrowPhase::with_query_dispatcher) to use the cbvh tree instead.",
                self.inner.triangles,
                self.inner.codec.name()
            );
            let leaves: Vec<PAabb> = with_cursor!(self, |c| (0..c.triangle_count() as u32)
                .map(|id| to_parry_aabb(&Aabb::of_triangle(&c.triangle(id))))
                .collect());
            Bvh::from_leaves(BvhBuildStrategy::default(), &leaves)
        })
    }
}

impl TypedCompositeShape for CbvhShape {
    type PartShape = PTriangle;
    type PartNormalConstraints = TrianglePseudoNormals;

    fn map_typed_part_at<T>(
        &self,
        shape_id: u32,
        mut f: impl FnMut(Option<&PPose>, &Self::PartShape, Option<&Self::PartNormalConstraints>) -> T,
    ) -> Option<T> {
        if shape_id as usize >= self.inner.triangles {
            return None;
        }
        let tri = self.parry_triangle(shape_id);
        Some(f(None, &tri, None))
    }

    fn map_untyped_part_at<T>(
        &self,
        shape_id: u32,
        mut f: impl FnMut(Option<&PPose>, &dyn Shape, Option<&dyn NormalConstraints>) -> T,
    ) -> Option<T> {
        if shape_id as usize >= self.inner.triangles {
            return None;
        }
        let tri = self.parry_triangle(shape_id);
        Some(f(None, &tri, None))
    }
}
