//! The render loop: tiles in parallel with rayon, deterministic.
//!
//! Every pixel is computed from its own primary ray, with no state shared
//! between pixels, and the counters are integer sums, so the image and the
//! counters are the same whatever the number of threads. Primary rays are
//! cast in packets of 8×8 pixels ([`Scene::closest_packet`]), which give
//! the hits of single rays exactly; node visits of a packet count once in
//! the traversal counters, not once per ray. (A codec whose own single-ray
//! traversal is faster casts a packet's rays one by one, and counts them
//! so: CLBVH, see
//! [`RayCursor::closest_hits_within`](crate::query::RayCursor::closest_hits_within).)

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::camera::Camera;
use super::error::RenderError;
use super::image::Image;
use super::scene::{Instance, Material, Scene, VertexNormals};
use super::shade::{RayCounts, Shading, auto_lights};
use super::target::CursorTarget;
use crate::build::{BuildOptions, build};
use crate::codec::plain::PlainBvh;
use crate::geom::Pose;
use crate::mesh::Mesh;
use crate::query::packet::MAX_PACKET;

/// Render settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Number of point lights ([`auto_lights`]).
    pub lights: usize,
    /// Mirror bounces (0: none).
    pub reflect_depth: u32,
    /// Whether to cast shadow rays.
    pub shadows: bool,
    /// Camera direction around the vertical axis, degrees (0: from +z).
    pub azimuth_deg: f32,
    /// Camera elevation above the horizon, degrees.
    pub elevation_deg: f32,
    /// Vertical field of view, degrees.
    pub fov_deg: f32,
    /// Whether to draw the ground plane.
    pub ground: bool,
    /// Tile edge in pixels (the unit of parallel work).
    pub tile: u32,
}

impl Default for RenderOptions {
    /// 800 × 600, 3 lights, shadows, 2 reflection bounces, ground.
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            lights: 3,
            reflect_depth: 2,
            shadows: true,
            azimuth_deg: 25.0,
            elevation_deg: 18.0,
            fov_deg: 35.0,
            ground: true,
            tile: 16,
        }
    }
}

impl RenderOptions {
    /// Primary rays only: no shadow rays, no reflections (lights still shade).
    pub fn primary_only(mut self) -> Self {
        self.shadows = false;
        self.reflect_depth = 0;
        self
    }
}

/// Camera and lighting of one frame.
#[derive(Clone, Debug)]
pub struct View {
    /// The camera.
    pub camera: Camera,
    /// Lights, ground, bounces.
    pub shading: Shading,
}

impl View {
    /// The automatic view of `scene`: the camera frames the scene bounds
    /// from `opts`' direction, lights around it, ground under the lowest point.
    pub fn auto(scene: &Scene, opts: &RenderOptions) -> Self {
        let b = scene.bounds();
        let camera = Camera::frame(
            &b,
            opts.azimuth_deg,
            opts.elevation_deg,
            opts.fov_deg,
            opts.width,
            opts.height,
        );
        let mut shading = Shading::for_bounds(
            &b,
            auto_lights(&b, opts.azimuth_deg, opts.lights),
            opts.shadows,
            opts.reflect_depth,
        );
        if !opts.ground {
            shading.ground_y = None;
        }
        Self { camera, shading }
    }
}

/// What a render measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct RenderStats {
    /// Rays by kind, and traversal counters.
    pub rays: RayCounts,
    /// Wall-clock seconds of the render (tracing and shading).
    pub seconds: f64,
    /// Threads of the rayon pool it ran in.
    pub threads: usize,
}

impl RenderStats {
    /// Rays per second over all ray kinds.
    pub fn rays_per_second(&self) -> f64 {
        self.rays.total() as f64 / self.seconds.max(1e-12)
    }
}

fn check_size(opts: &RenderOptions) -> Result<(), RenderError> {
    if opts.width == 0 || opts.height == 0 {
        return Err(RenderError::ZeroSize {
            width: opts.width,
            height: opts.height,
        });
    }
    Ok(())
}

/// Renders `scene` with the automatic [`View`]. `progress(done, total)`
/// is called (from any thread) as tiles complete.
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats), RenderError> {
    render_view(scene, &View::auto(scene, opts), opts, progress)
}

/// Renders `scene` from `view` at `opts`' size and tile size (the view's
/// own settings decide shadows and bounces), in the current rayon pool.
pub fn render_view(
    scene: &Scene,
    view: &View,
    opts: &RenderOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats), RenderError> {
    check_size(opts)?;
    let (w, h) = (opts.width, opts.height);
    let tile = opts.tile.max(1);
    let (tx, ty) = (w.div_ceil(tile), h.div_ceil(tile));
    let total = tx as u64 * ty as u64;
    let done = AtomicU64::new(0);
    let start = Instant::now();
    let tiles: Vec<(u32, u32, u32, u32, Vec<u8>, RayCounts)> = (0..total)
        .into_par_iter()
        .map(|i| {
            let (x0, y0) = ((i % tx as u64) as u32 * tile, (i / tx as u64) as u32 * tile);
            let (bw, bh) = (tile.min(w - x0), tile.min(h - y0));
            let mut block = Image::new(bw, bh);
            let mut counts = RayCounts::default();
            // Primary rays in packets of 8×8 pixels (one traversal per
            // mesh for the packet; the same hits as ray by ray).
            let mut rays = Vec::with_capacity(MAX_PACKET);
            let mut hits = [None; MAX_PACKET];
            for py in (0..bh).step_by(8) {
                for px in (0..bw).step_by(8) {
                    rays.clear();
                    for y in py..(py + 8).min(bh) {
                        for x in px..(px + 8).min(bw) {
                            rays.push(view.camera.primary_ray(x0 + x, y0 + y, w, h));
                        }
                    }
                    let hits = &mut hits[..rays.len()];
                    scene.closest_packet(&rays, hits, &mut counts.traversal);
                    let pw = (px + 8).min(bw) - px;
                    for (k, (ray, hit)) in rays.iter().zip(hits.iter()).enumerate() {
                        counts.primary += 1;
                        let c = view.shading.trace_hit(scene, ray, *hit, 0, &mut counts);
                        let k = k as u32;
                        block.set_linear(px + k % pw, py + k / pw, c);
                    }
                }
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            (x0, y0, bw, bh, block.data().to_vec(), counts)
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let mut image = Image::new(w, h);
    let mut rays = RayCounts::default();
    for (x0, y0, bw, bh, block, counts) in &tiles {
        image.blit(*x0, *y0, *bw, *bh, block);
        rays.add(counts);
    }
    Ok((
        image,
        RenderStats {
            rays,
            seconds,
            threads: rayon::current_num_threads(),
        },
    ))
}

/// `frames` images of a turntable: the camera and the lights circle the
/// scene's vertical axis together, starting at `opts.azimuth_deg`.
/// `progress(done, total)` counts tiles over all frames.
pub fn render_turntable(
    scene: &Scene,
    opts: &RenderOptions,
    frames: u32,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Vec<Image>, RenderStats), RenderError> {
    if frames == 0 {
        return Err(RenderError::NoFrames);
    }
    check_size(opts)?;
    let per_frame = opts.width.div_ceil(opts.tile.max(1)) as u64
        * opts.height.div_ceil(opts.tile.max(1)) as u64;
    let total = per_frame * frames as u64;
    let mut images = Vec::with_capacity(frames as usize);
    let mut stats = RenderStats::default();
    for f in 0..frames {
        let mut o = opts.clone();
        o.azimuth_deg = opts.azimuth_deg + 360.0 * f as f32 / frames as f32;
        let base = per_frame * f as u64;
        let (img, s) = render(scene, &o, &|d, _| progress(base + d, total))?;
        images.push(img);
        stats.rays.add(&s.rays);
        stats.seconds += s.seconds;
        stats.threads = s.threads;
    }
    Ok((images, stats))
}

/// Renders meshes placed with poses (the drop-test sims' final frame):
/// builds a plain BVH and smooth normals for each distinct mesh (a mesh
/// given several times, by reference, is built once), gives instances the
/// [`Material::PALETTE`] colours in turn, and renders with the automatic
/// view.
pub fn render_meshes(meshes: &[(&Mesh, Pose)], opts: &RenderOptions) -> Result<Image, RenderError> {
    check_size(opts)?;
    let mut slot: HashMap<*const Mesh, usize> = HashMap::new();
    let mut built: Vec<(CursorTarget<PlainBvh>, VertexNormals)> = Vec::new();
    let mut which = Vec::with_capacity(meshes.len());
    for (i, (mesh, _)) in meshes.iter().enumerate() {
        let key: *const Mesh = *mesh;
        let k = match slot.get(&key) {
            Some(&k) => k,
            None => {
                let bvh = build(mesh, &BuildOptions::default(), &|_, _| {})
                    .map_err(|source| RenderError::Build { mesh: i, source })?;
                built.push((
                    CursorTarget::new(PlainBvh::new(&bvh, mesh)),
                    VertexNormals::from_mesh(mesh),
                ));
                slot.insert(key, built.len() - 1);
                built.len() - 1
            }
        };
        which.push(k);
    }
    let instances = meshes
        .iter()
        .zip(&which)
        .enumerate()
        .map(|(i, ((_, pose), &k))| Instance {
            target: &built[k].0,
            pose: *pose,
            normals: Some(&built[k].1),
            material: Material::PALETTE[i % Material::PALETTE.len()],
        })
        .collect();
    let scene = Scene::new(instances);
    Ok(render(&scene, opts, &|_, _| {})?.0)
}
