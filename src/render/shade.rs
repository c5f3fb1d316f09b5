//! Whitted-style shading: point lights with shadow rays, Lambert + Phong,
//! mirror reflections, a ground plane and a background gradient.

use glam::Vec3A;

use super::scene::{Material, Scene, SceneHit, Surface};
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Ray};

/// A point light (no distance falloff, so exposure does not depend on the
/// scene's scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Position (world).
    pub position: Vec3A,
    /// Linear RGB intensity.
    pub color: Vec3A,
}

/// `count` lights around `bounds`, placed relative to a camera looking from
/// `azimuth_deg`: a warm key light up and to the left of the camera, then
/// cooler, weaker fill and rim lights spread around the vertical axis.
/// The key light carries three quarters of a fixed total intensity, the
/// others share the rest, whatever `count` is.
pub fn auto_lights(bounds: &Aabb, azimuth_deg: f32, count: usize) -> Vec<Light> {
    if count == 0 {
        return Vec::new();
    }
    let b = if bounds.is_empty() {
        Aabb::from_arrays([-1.0; 3], [1.0; 3])
    } else {
        *bounds
    };
    let center = b.center();
    let radius = b.half_extents().length().max(1e-6);
    let mut lights = Vec::with_capacity(count);
    let mut weights = Vec::with_capacity(count);
    for i in 0..count {
        // Key: 65° left of the camera, 50° up. Others: spread evenly over
        // the rest of the circle, lower.
        let (az, el, w, tint) = if i == 0 {
            (azimuth_deg - 65.0, 50.0, 1.0, Vec3A::new(1.0, 0.95, 0.86))
        } else {
            let step = 260.0 / count as f32;
            let az = azimuth_deg + 40.0 + step * (i - 1) as f32 + step * 0.5;
            let el = if i % 2 == 1 { 35.0 } else { 60.0 };
            (
                az,
                el,
                0.35 / (count - 1) as f32,
                Vec3A::new(0.86, 0.92, 1.0),
            )
        };
        let (az, el) = (f32::to_radians(az), f32::to_radians(el));
        let dir = Vec3A::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        lights.push(Light {
            position: center + dir * (radius * 4.0),
            color: tint,
        });
        weights.push(w);
    }
    let total: f32 = weights.iter().sum();
    for (l, w) in lights.iter_mut().zip(weights) {
        l.color *= 1.1 * w / total;
    }
    lights
}

/// Everything a ray needs besides the scene.
#[derive(Clone, Debug)]
pub struct Shading {
    /// The lights.
    pub lights: Vec<Light>,
    /// Height of the ground plane (`None`: no ground).
    pub ground_y: Option<f32>,
    /// Size of a ground checker square.
    pub checker: f32,
    /// Distance over which the ground fades into the background.
    pub fog_distance: f32,
    /// Offset of secondary ray origins along the normal.
    pub epsilon: f32,
    /// Whether to cast shadow rays.
    pub shadows: bool,
    /// Reflection bounces (0: none).
    pub reflect_depth: u32,
    /// Ambient light (linear RGB).
    pub ambient: Vec3A,
}

impl Shading {
    /// Settings for a scene with `bounds`: ground just under the lowest point.
    pub fn for_bounds(
        bounds: &Aabb,
        lights: Vec<Light>,
        shadows: bool,
        reflect_depth: u32,
    ) -> Self {
        let b = if bounds.is_empty() {
            Aabb::from_arrays([-1.0; 3], [1.0; 3])
        } else {
            *bounds
        };
        let size = b.extent().max_element().max(1e-6);
        let magnitude = b.min.abs().max(b.max.abs()).max_element();
        Self {
            lights,
            ground_y: Some(b.min.y - size * 1e-4),
            checker: size / 8.0,
            fog_distance: size * 12.0,
            epsilon: size * 2e-5 + magnitude * 4.0 * f32::EPSILON,
            shadows,
            reflect_depth,
            ambient: Vec3A::new(0.1, 0.11, 0.13),
        }
    }
}

/// Counters of one render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Rays towards lights.
    pub shadow: u64,
    /// Mirror rays.
    pub reflection: u64,
    /// Traversal counters over all rays.
    pub traversal: TraversalStats,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflection
    }

    /// Adds another set of counters.
    pub fn add(&mut self, o: &RayCounts) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.traversal.add(&o.traversal);
    }
}

/// The background gradient seen along unit direction `dir`.
pub fn background(dir: Vec3A) -> Vec3A {
    let horizon = Vec3A::new(0.78, 0.81, 0.86);
    let zenith = Vec3A::new(0.25, 0.38, 0.62);
    let below = Vec3A::new(0.5, 0.5, 0.52);
    if dir.y >= 0.0 {
        horizon.lerp(zenith, dir.y.sqrt())
    } else {
        horizon.lerp(below, (-dir.y).sqrt())
    }
}

const GROUND: Material = Material::new([0.6, 0.6, 0.6], 0.08, 20.0, 0.12);

impl Shading {
    fn ground_hit(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let y = self.ground_y?;
        if ray.dir.y == 0.0 {
            return None;
        }
        let t = (y - ray.origin.y) / ray.dir.y;
        (t > 0.0 && t < t_max).then_some(t)
    }

    fn ground_color(&self, p: Vec3A) -> Vec3A {
        let (i, j) = (
            (p.x / self.checker).floor() as i64,
            (p.z / self.checker).floor() as i64,
        );
        let c = if (i + j) & 1 == 0 { 0.36 } else { 0.29 };
        Vec3A::new(c, c * 0.97, c * 0.93)
    }

    fn occluded(&self, scene: &Scene, ray: &Ray, dist: f32, counts: &mut RayCounts) -> bool {
        counts.shadow += 1;
        self.ground_hit(ray, dist).is_some() || scene.any(ray, dist, &mut counts.traversal)
    }

    /// The colour seen along `ray` (unit direction), `depth` bounces deep.
    pub fn trace(&self, scene: &Scene, ray: &Ray, depth: u32, counts: &mut RayCounts) -> Vec3A {
        let hit = scene.closest(ray, f32::INFINITY, &mut counts.traversal);
        self.trace_hit(scene, ray, hit, depth, counts)
    }

    /// [`Shading::trace`] given the meshes' closest hit along `ray` (from
    /// [`Scene::closest`] or [`Scene::closest_packet`]).
    pub fn trace_hit(
        &self,
        scene: &Scene,
        ray: &Ray,
        hit: Option<SceneHit>,
        depth: u32,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let t_mesh = hit.map_or(f32::INFINITY, |h| h.hit.t);
        let (surface, fog) = match (self.ground_hit(ray, t_mesh), hit) {
            (Some(t), _) => {
                let point = ray.at(t);
                let mut material = GROUND;
                material.color = self.ground_color(point);
                let n = Vec3A::Y * -ray.dir.y.signum();
                let s = Surface {
                    point,
                    geometric: n,
                    shading: n,
                    material,
                };
                (s, 1.0 - (-t / self.fog_distance).exp())
            }
            (None, Some(h)) => (scene.surface(ray, &h), 0.0),
            (None, None) => return background(ray.dir),
        };
        let color = self.shade(scene, ray, &surface, depth, counts);
        color.lerp(background(ray.dir), fog * fog)
    }

    fn shade(
        &self,
        scene: &Scene,
        ray: &Ray,
        s: &Surface,
        depth: u32,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let m = &s.material;
        let n = s.shading;
        let origin = s.point + s.geometric * self.epsilon;
        // Hemispherical ambient: a little brighter facing up.
        let mut color = self.ambient * m.color * (0.6 + 0.4 * n.y);
        let view = -ray.dir;
        for light in &self.lights {
            let to_light = light.position - origin;
            let dist = to_light.length();
            let l = to_light / dist;
            let ndotl = n.dot(l);
            if ndotl <= 0.0 || s.geometric.dot(l) <= 0.0 {
                continue;
            }
            if self.shadows && self.occluded(scene, &Ray::new(origin, l), dist, counts) {
                continue;
            }
            let r = 2.0 * ndotl * n - l;
            let rv = r.dot(view);
            let spec = if rv > 0.0 {
                m.specular * rv.powf(m.shininess)
            } else {
                0.0
            };
            color += light.color * (m.color * ndotl + Vec3A::splat(spec));
        }
        if depth < self.reflect_depth && m.reflectivity > 0.0 {
            let d = ray.dir - 2.0 * ray.dir.dot(n) * n;
            // Keep the mirror ray above the surface.
            let d = if d.dot(s.geometric) <= 0.0 {
                ray.dir - 2.0 * ray.dir.dot(s.geometric) * s.geometric
            } else {
                d
            };
            counts.reflection += 1;
            let reflected = self.trace(scene, &Ray::new(origin, d.normalize()), depth + 1, counts);
            color = color * (1.0 - m.reflectivity) + reflected * m.reflectivity;
        }
        color
    }
}
