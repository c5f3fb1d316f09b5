//! A Whitted-style CPU ray tracer that renders directly from the
//! acceleration structures: any [`NodeCursor`](crate::cursor::NodeCursor)
//! (through [`crate::query::ray`]) and parry's `TriMesh` (for comparison),
//! behind one small trait, [`RayTarget`].
//!
//! - [`target`]: [`RayTarget`] and [`CursorTarget`], the adapter for every
//!   [`Codec`](crate::codec::Codec) (any codec of the registry through
//!   [`any_target`]), so a new codec renders with nothing added here.
//! - [`scene`]: [`Scene`]s of [`Instance`]s (a target placed with a
//!   [`Pose`](crate::geom::Pose), a [`Material`], optional smooth
//!   [`VertexNormals`]); a single mesh is a scene of one.
//! - [`camera`]: the pinhole [`Camera`] and automatic framing of the
//!   scene bounds.
//! - [`shade`]: point [`Light`]s with shadow rays (the any-hit query),
//!   Lambert + Phong, mirror reflections to a settable depth, a checkered
//!   ground plane just under the lowest point that fades into a
//!   background gradient.
//! - [`trace`]: the render loop, parallel over tiles with rayon and
//!   deterministic (the image does not depend on the number of threads),
//!   turntables, and [`render_meshes`] for the drop-test sims.
//! - [`image`]: the 8-bit sRGB [`Image`]; with the `image-files` feature,
//!   PNG output, and animated PNG or GIF for turntables.
//!
//! Shading normals are area-weighted vertex normals, computed once per
//! mesh, interpolated with the hit's barycentrics; a triangle touching a
//! vertex without a normal, or a target that does not expose vertex
//! indices, is shaded with its face normal.
//!
//! ```no_run
//! # #[cfg(feature = "image-files")] {
//! use cbvh::render::{RenderOptions, render_meshes};
//! # let mesh = cbvh::Mesh::default();
//! let image = render_meshes(&[(&mesh, cbvh::geom::Pose::IDENTITY)], &RenderOptions::default())?;
//! image.save_png("frame.png")?;
//! # }
//! # Ok::<(), cbvh::render::RenderError>(())
//! ```

pub mod camera;
pub mod error;
pub mod image;
pub mod scene;
pub mod shade;
pub mod target;
pub mod trace;

pub use camera::Camera;
pub use error::RenderError;
pub use image::Image;
#[cfg(feature = "image-files")]
pub use image::{save_animation, save_apng, save_gif};
pub use scene::{Instance, Material, Scene, SceneHit, Surface, VertexNormals};
pub use shade::{Light, RayCounts, Shading, auto_lights, background};
pub use target::{CursorTarget, RayTarget, any_target};
pub use trace::{
    RenderOptions, RenderStats, View, render, render_meshes, render_turntable, render_view,
};
