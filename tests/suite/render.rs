//! The ray tracer: same image whatever the tree, close to parry's, shadows
//! darken, threads do not change the image, and the CLI's errors.

use crate::common::{cbvh, in_pool, tree};
use std::path::PathBuf;

use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::geom::{Aabb, Pose, Ray};
use cbvh::render::{
    Camera, CursorTarget, Image, Instance, Light, Material, RayTarget, RenderOptions, Scene,
    Shading, VertexNormals, View, render, render_meshes, render_turntable, render_view,
    save_animation, save_apng,
};
use cbvh::scene::{Kind, generate};
use cbvh::{Mesh, TraversalStats};
use glam::{Quat, Vec3, Vec3A};

fn statue() -> Mesh {
    generate(Kind::Statue, 2_000, 7, &mut |_, _| {}).expect("generate")
}

fn robot() -> Mesh {
    generate(Kind::Robot, 1_500, 3, &mut |_, _| {}).expect("generate")
}

fn plain(mesh: &Mesh, layout: Layout, leaf: usize) -> CursorTarget<PlainBvh> {
    CursorTarget::new(PlainBvh::new(&tree(mesh, layout, leaf), mesh))
}

/// An axis-aligned box as a closed mesh, outward counter-clockwise.
fn cube(min: [f32; 3], max: [f32; 3]) -> Mesh {
    Mesh::cuboid(min, max)
}

fn small() -> RenderOptions {
    RenderOptions {
        width: 96,
        height: 72,
        tile: 8,
        ..Default::default()
    }
}

fn two_poses() -> [Pose; 2] {
    [
        Pose::IDENTITY,
        Pose::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(1.3, 0.0, -0.4)),
    ]
}

/// A scene of a statue and a rotated robot, over whatever targets.
fn scene_of<'a, T: RayTarget>(targets: &'a [T; 2], normals: &'a [VertexNormals; 2]) -> Scene<'a> {
    let poses = two_poses();
    Scene::new(
        (0..2)
            .map(|i| Instance {
                target: &targets[i],
                pose: poses[i],
                normals: Some(&normals[i]),
                material: Material::PALETTE[i],
            })
            .collect(),
    )
}

/// What other targets' images are compared against: the statue and the
/// robot, their vertex normals, plain targets (depth-first, one triangle
/// per leaf), and a 160×120 frame.
struct Reference {
    meshes: [Mesh; 2],
    normals: [VertexNormals; 2],
    plain: [CursorTarget<PlainBvh>; 2],
    opts: RenderOptions,
}

impl Reference {
    /// The two-instance scene over `targets` (the statue's, the robot's)
    /// with the reference normals.
    fn scene<'a, T: RayTarget>(&'a self, targets: &'a [T; 2]) -> Scene<'a> {
        scene_of(targets, &self.normals)
    }
}

fn reference() -> Reference {
    let meshes = [statue(), robot()];
    Reference {
        normals: meshes.each_ref().map(VertexNormals::from_mesh),
        plain: meshes.each_ref().map(|m| plain(m, Layout::DepthFirst, 1)),
        opts: RenderOptions {
            width: 160,
            height: 120,
            ..small()
        },
        meshes,
    }
}

fn empty_render(opts: &RenderOptions) -> Image {
    let scene = Scene::new(Vec::new());
    render(&scene, opts, &|_, _| {}).expect("render").0
}

#[test]
fn every_layout_and_leaf_size_renders_the_same_image() {
    let (s, r) = (statue(), robot());
    let normals = [VertexNormals::from_mesh(&s), VertexNormals::from_mesh(&r)];
    let opts = small();
    let base_t = [
        plain(&s, Layout::DepthFirst, 1),
        plain(&r, Layout::DepthFirst, 1),
    ];
    let (base, base_stats) =
        render(&scene_of(&base_t, &normals), &opts, &|_, _| {}).expect("render");
    // The scene is really in the picture, with shadows and reflections.
    assert!(base.fraction_differing(&empty_render(&opts)) > 0.15);
    assert!(base_stats.rays.shadow > 0 && base_stats.rays.reflection > 0);
    for layout in Layout::ALL {
        for leaf in [1, 4] {
            let t = [plain(&s, layout, leaf), plain(&r, layout, leaf)];
            let (img, stats) = render(&scene_of(&t, &normals), &opts, &|_, _| {}).expect("render");
            assert_eq!(img.fraction_differing(&base), 0.0, "{layout} leaf {leaf}");
            assert_eq!(img, base, "{layout} leaf {leaf}");
            assert_eq!(
                (stats.rays.primary, stats.rays.shadow, stats.rays.reflection),
                (
                    base_stats.rays.primary,
                    base_stats.rays.shadow,
                    base_stats.rays.reflection
                )
            );
        }
    }
}

/// RACBVH renders the plain codec's image from the same camera: pixel for
/// pixel with lossless (f32) vertices (its quantized boxes are
/// conservative, so the hits are the same), also with a cache far smaller
/// than the tree, and within 0.5 % of the pixels with 16-bit vertices
/// (lossy).
#[test]
fn racbvh_renders_the_plain_image_exactly_when_lossless_and_nearly_when_lossy() {
    let reference = reference();
    let opts = &reference.opts;
    // One camera for all: the automatic view frames the scene's bounds, and
    // RACBVH's root box is its quantization grid, a few ulps larger.
    let plain_scene = reference.scene(&reference.plain);
    let view = View::auto(&plain_scene, opts);
    let (base, _) = render_view(&plain_scene, &view, opts, &|_, _| {}).expect("render");
    let rac = |m: &Mesh, vertex_bits: Option<u32>, budget: usize| {
        let tree = build(m, &BuildOptions::default(), &|_, _| {}).expect("build");
        let o = RacOptions {
            cluster_nodes: 256,
            vertex_bits,
            cache_budget_bytes: budget,
            ..Default::default()
        };
        CursorTarget::new(RacBvh::encode(&tree, m, &o).expect("encode"))
    };
    for (vertex_bits, budget, bound) in [
        (None, usize::MAX, 0.0),
        (None, 40_000, 0.0),
        (Some(16), usize::MAX, 0.005),
    ] {
        let t = reference
            .meshes
            .each_ref()
            .map(|m| rac(m, vertex_bits, budget));
        let (img, _) = render_view(&reference.scene(&t), &view, opts, &|_, _| {}).expect("render");
        let differ = img.fraction_differing(&base);
        eprintln!("racbvh {vertex_bits:?} bits, budget {budget}: {differ}");
        assert!(differ <= bound, "{vertex_bits:?} {budget}: {differ}");
        if bound == 0.0 {
            assert_eq!(img, base);
        }
    }
}

/// Measured: 2 of the 19 200 pixels (0.01 %) differ, where parry's and
/// Möller–Trumbore's triangle tests disagree at a silhouette; bound 0.5 %.
#[test]
fn parry_image_matches_plain_but_for_a_few_silhouette_pixels() {
    let reference = reference();
    let opts = &reference.opts;
    let q = reference
        .meshes
        .each_ref()
        .map(|m| cbvh::parry::parry_trimesh(m).unwrap());
    let (a, sa) = render(&reference.scene(&reference.plain), opts, &|_, _| {}).unwrap();
    let (b, sb) = render(&reference.scene(&q), opts, &|_, _| {}).unwrap();
    let diff = a.fraction_differing(&b);
    eprintln!("parry vs plain: {:.4} % of pixels differ", diff * 100.0);
    assert!(diff <= 0.005, "{diff}");
    assert!(a.fraction_differing(&empty_render(opts)) > 0.15);
    assert_eq!(sa.rays.primary, sb.rays.primary);
    // parry does not count traversal steps; plain does.
    assert!(sa.rays.traversal.nodes_visited > 0);
    assert_eq!(sb.rays.traversal, TraversalStats::default());
}

#[test]
fn scene_packets_give_the_single_ray_hits_over_posed_instances() {
    let (s, r) = (statue(), robot());
    let t = [
        plain(&s, Layout::DepthFirst, 1),
        plain(&r, Layout::VanEmdeBoas, 2),
    ];
    let normals = [VertexNormals::from_mesh(&s), VertexNormals::from_mesh(&r)];
    let scene = scene_of(&t, &normals);
    let b = scene.bounds();
    let mut stats = TraversalStats::default();
    let (mut hits, mut by_instance) = (0, [0; 2]);
    // 8×8 tiles of a camera looking at the two instances from several
    // sides, and partial packets.
    for (k, eye) in [
        Vec3A::new(0.0, 0.3, 1.6),
        Vec3A::new(-1.2, 0.4, -0.8),
        Vec3A::new(1.0, 1.2, 0.2),
    ]
    .into_iter()
    .enumerate()
    {
        let eye = b.center() + eye * b.extent().max_element();
        let fwd = (b.center() - eye).normalize();
        let right = fwd.cross(Vec3A::Y).normalize();
        let up = right.cross(fwd);
        for tile in 0..16 {
            let (tx, ty) = ((tile % 4) as f32, (tile / 4) as f32);
            let n = if tile == 5 { 37 } else { 64 };
            let rays: Vec<Ray> = (0..n)
                .map(|p| {
                    let x = (tx * 8.0 + (p % 8) as f32) / 32.0 - 0.5;
                    let y = (ty * 8.0 + (p / 8) as f32) / 32.0 - 0.5;
                    let d = fwd + right * x * (0.5 + 0.1 * k as f32) + up * y * 0.5;
                    Ray::new(eye, d.normalize())
                })
                .collect();
            let mut got = vec![None; n];
            scene.closest_packet(&rays, &mut got, &mut stats);
            for (ray, g) in rays.iter().zip(&got) {
                let want = scene.closest(ray, f32::INFINITY, &mut stats);
                assert_eq!(
                    g.map(|h| (h.instance, h.hit)),
                    want.map(|h| (h.instance, h.hit)),
                    "{ray:?}"
                );
                if let Some(h) = g {
                    hits += 1;
                    by_instance[h.instance] += 1;
                }
            }
        }
    }
    assert!(
        hits > 500 && by_instance.iter().all(|&c| c > 50),
        "{hits} {by_instance:?}"
    );
}

#[test]
fn parry_target_agrees_with_plain_ray_by_ray() {
    let s = statue();
    let p = plain(&s, Layout::DepthFirst, 1);
    let q = cbvh::parry::parry_trimesh(&s).unwrap();
    let b = RayTarget::bounds(&p);
    assert!((RayTarget::bounds(&q).min - b.min).abs().max_element() < 1e-5);
    let mut stats = TraversalStats::default();
    let (mut hits, mut agree, mut any_agree) = (0, 0, 0);
    let n = 2_000;
    for i in 0..n {
        // Rays from a sphere around the statue towards points inside its box.
        let a = i as f32 * 2.399_963;
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let o = b.center()
            + Vec3A::new(
                (1.0 - z * z).sqrt() * a.cos(),
                z,
                (1.0 - z * z).sqrt() * a.sin(),
            ) * 3.0;
        let f = |k: f32| (k * 0.618_034).fract();
        let target =
            b.min + b.extent() * Vec3A::new(f(i as f32), f(i as f32 + 0.3), f(i as f32 + 0.7));
        let ray = Ray::new(o, (target - o).normalize());
        let hp = p.closest(&ray, f32::INFINITY, &mut stats);
        let hq = q.closest(&ray, f32::INFINITY, &mut stats);
        if let (Some(x), Some(y)) = (hp, hq) {
            hits += 1;
            if (x.t - y.t).abs() < 1e-4 {
                agree += 1;
                // Barycentrics recomputed from parry's hit point give the same point.
                let (tp, tq) = (p.triangle(x.triangle), RayTarget::triangle(&q, y.triangle));
                let pp = tp[0] * (1.0 - x.u - x.v) + tp[1] * x.u + tp[2] * x.v;
                let pq = tq[0] * (1.0 - y.u - y.v) + tq[1] * y.u + tq[2] * y.v;
                assert!((pp - pq).length() < 1e-3, "{pp} {pq}");
            }
        } else if hp.is_none() && hq.is_none() {
            agree += 1;
        }
        let d = hp.map_or(2.0, |h| h.t * 0.999);
        if p.any(&ray, d, &mut stats) == q.any(&ray, d, &mut stats) {
            any_agree += 1;
        }
    }
    eprintln!("{hits} hits; closest agrees on {agree}, any on {any_agree} of {n} rays");
    assert!(hits > n / 3, "{hits}");
    assert!(agree >= n * 995 / 1000, "{agree} of {n}");
    assert!(any_agree >= n * 995 / 1000, "{any_agree} of {n}");
}

#[test]
fn a_point_in_shadow_is_darker_than_the_same_point_lit() {
    // A box floats above the ground point (0, 0, 0), straight under the
    // only light; the camera looks at that point from the side.
    let occluder = cube([-0.25, 1.8, -0.25], [0.25, 2.2, 0.25]);
    let t = plain(&occluder, Layout::DepthFirst, 1);
    let opts = RenderOptions {
        width: 33,
        height: 33,
        ..small()
    };
    let camera = Camera::look_at(
        Vec3A::new(3.0, 1.5, 0.0),
        Vec3A::ZERO,
        30.0,
        opts.width,
        opts.height,
    );
    let light = Light {
        position: Vec3A::new(0.0, 6.0, 0.0),
        color: Vec3A::ONE,
    };
    let mut shading = Shading::for_bounds(
        &Aabb::from_arrays([-1.0; 3], [1.0; 3]),
        vec![light],
        true,
        0,
    );
    shading.ground_y = Some(0.0);
    let view = View { camera, shading };
    let render_at = |pose: Pose| {
        let scene = Scene::new(vec![Instance::new(&t, pose, None)]);
        render_view(&scene, &view, &opts, &|_, _| {}).unwrap()
    };
    // Occluding, and moved aside (behind the camera: same point, lit).
    let (shadowed, s1) = render_at(Pose::IDENTITY);
    let away = Pose::from_rotation_translation(Quat::IDENTITY, Vec3::new(20.0, 0.0, 0.0));
    let (lit, _) = render_at(away);
    let (dark, bright) = (shadowed.mean_around(16, 16, 1), lit.mean_around(16, 16, 1));
    eprintln!("shadowed {dark:.1}, lit {bright:.1}");
    assert!(dark < 0.6 * bright, "{dark} {bright}");
    assert!(s1.rays.shadow > 0);
    // Without shadow rays the two look the same at that point.
    let mut view2 = view.clone();
    view2.shading.shadows = false;
    let scene = Scene::new(vec![Instance::new(&t, Pose::IDENTITY, None)]);
    let (no_shadow, s2) = render_view(&scene, &view2, &opts, &|_, _| {}).unwrap();
    assert_eq!(no_shadow.pixel(16, 16), lit.pixel(16, 16));
    assert_eq!(s2.rays.shadow, 0);
}

#[test]
fn multithreaded_image_equals_single_threaded() {
    let (s, r) = (statue(), robot());
    let normals = [VertexNormals::from_mesh(&s), VertexNormals::from_mesh(&r)];
    let t = [
        plain(&s, Layout::VanEmdeBoas, 1),
        plain(&r, Layout::CacheEfficient, 2),
    ];
    let scene = scene_of(&t, &normals);
    let opts = RenderOptions { tile: 5, ..small() };
    let run = |threads: usize| in_pool(threads, || render(&scene, &opts, &|_, _| {}).unwrap());
    let (one, s1) = run(1);
    assert_eq!(s1.threads, 1);
    for threads in [2, 3] {
        let (img, s) = run(threads);
        assert_eq!(s.threads, threads);
        assert_eq!(img, one, "{threads} threads");
        assert_eq!(s.rays, s1.rays, "{threads} threads");
    }
}

#[test]
fn smooth_normals_change_the_shading_and_face_normals_remain_for_opaque_targets() {
    let s = statue();
    let normals = VertexNormals::from_mesh(&s);
    let smooth = plain(&s, Layout::DepthFirst, 1);
    let flat = CursorTarget::new(PlainBvh::new(
        &build(&s, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &s,
    ))
    .flat();
    assert!(flat.vertex_indices(0).is_none() && smooth.vertex_indices(0).is_some());
    let opts = small();
    let a = render(&Scene::single(&smooth, Some(&normals)), &opts, &|_, _| {})
        .unwrap()
        .0;
    let b = render(&Scene::single(&flat, Some(&normals)), &opts, &|_, _| {})
        .unwrap()
        .0;
    let c = render(&Scene::single(&smooth, None), &opts, &|_, _| {})
        .unwrap()
        .0;
    assert!(
        a.fraction_differing(&b) > 0.02,
        "{}",
        a.fraction_differing(&b)
    );
    assert_eq!(b, c);
}

#[test]
fn vertex_normals_are_area_weighted_and_degenerate_ones_are_absent() {
    let c = cube([0.0; 3], [1.0; 3]);
    let n = VertexNormals::from_mesh(&c);
    assert_eq!(n.len(), 8);
    // Each corner touches two triangles on one face and one or two on the
    // others: area weighting over the corner's faces is not symmetric, but
    // the normal points out of the cube, into the corner's octant.
    for i in 0..8u32 {
        let v = n.get(i).unwrap();
        assert!((v.length() - 1.0).abs() < 1e-5);
        let corner = Vec3A::from(c.vertices[i as usize]) - Vec3A::splat(0.5);
        assert!(v.dot(corner) > 0.0);
    }
    // A vertex used by no triangle, or only by a degenerate one, has none.
    let m = Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [5.0; 3]],
        vec![[0, 1, 2]],
    );
    let n = VertexNormals::from_mesh(&m);
    assert!((0..4).all(|i| n.get(i).is_none()));
    assert!(n.get(99).is_none());
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("cbvh-render-{}-{name}", std::process::id()))
}

fn decode(path: &PathBuf) -> (png::OutputInfo, Vec<u8>, Option<u32>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let frames = reader.info().animation_control.map(|a| a.num_frames);
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info, buf, frames)
}

#[test]
fn render_meshes_saves_a_png_that_decodes_to_the_image() {
    let (s, r) = (statue(), robot());
    let [p0, p1] = two_poses();
    let opts = small();
    let img = render_meshes(
        &[
            (&s, p0),
            (&r, p1),
            (
                &r,
                Pose::from_rotation_translation(Quat::IDENTITY, Vec3::new(-1.2, 0.0, 0.3)),
            ),
        ],
        &opts,
    )
    .unwrap();
    assert!(img.fraction_differing(&empty_render(&opts)) > 0.15);
    let path = temp("meshes.png");
    img.save_png(&path).unwrap();
    let (info, data, frames) = decode(&path);
    assert_eq!((info.width, info.height), (96, 72));
    assert_eq!(data, img.data());
    assert_eq!(frames, None);
    std::fs::remove_file(&path).ok();
    let bad = RenderOptions {
        width: 0,
        ..small()
    };
    let e = render_meshes(&[(&s, p0)], &bad).unwrap_err();
    assert!(e.to_string().contains("0 × 72"), "{e}");
}

#[test]
fn turntable_is_an_animated_png_of_distinct_frames() {
    let s = statue();
    let normals = VertexNormals::from_mesh(&s);
    let t = plain(&s, Layout::DepthFirst, 1);
    let scene = Scene::single(&t, Some(&normals));
    let opts = RenderOptions {
        width: 24,
        height: 18,
        ..small()
    };
    let (frames, stats) = render_turntable(&scene, &opts, 3, &|_, _| {}).unwrap();
    assert_eq!(frames.len(), 3);
    assert_eq!(stats.rays.primary, 3 * 24 * 18);
    assert!(frames[0] != frames[1] && frames[1] != frames[2]);
    assert_eq!(frames[0], render(&scene, &opts, &|_, _| {}).unwrap().0);
    let path = temp("turn.png");
    save_apng(&frames, &path, 12).unwrap();
    let (info, data, n) = decode(&path);
    assert_eq!(n, Some(3));
    assert_eq!((info.width, info.height), (24, 18));
    assert_eq!(data, frames[0].data());
    std::fs::remove_file(&path).ok();
    assert!(save_apng(&[], &path, 12).is_err());
    // GIF: the same frames, quantised; the file is a looping 3-frame GIF.
    let gif_path = temp("turn.gif");
    save_animation(&frames, &gif_path, 12).unwrap();
    let mut dopts = gif::DecodeOptions::new();
    dopts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = dopts
        .read_info(std::fs::File::open(&gif_path).unwrap())
        .unwrap();
    assert_eq!((dec.width(), dec.height()), (24, 18));
    let mut n = 0;
    while let Some(f) = dec.read_next_frame().unwrap() {
        assert_eq!(f.delay, 8);
        // Quantisation keeps colours close: mean error under 3 levels.
        let err: f64 = f
            .buffer
            .chunks_exact(4)
            .zip(frames[n].data().chunks_exact(3))
            .map(|(a, b)| {
                (0..3)
                    .map(|k| (a[k] as f64 - b[k] as f64).abs())
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (24.0 * 18.0 * 3.0);
        assert!(err < 3.0, "frame {n}: {err}");
        n += 1;
    }
    assert_eq!(n, 3);
    std::fs::remove_file(&gif_path).ok();
    assert!(render_turntable(&scene, &opts, 0, &|_, _| {}).is_err());
}

#[test]
fn cli_renders_and_reports_json() {
    let out = temp("cli.png");
    let anim = temp("cli-anim.png");
    let (ok, stdout, stderr) = cbvh(&[
        "render",
        "--gen",
        "robot",
        "--tris",
        "1000",
        "--codec",
        "plain",
        "--width",
        "20",
        "--height",
        "16",
        "--lights",
        "2",
        "--reflect-depth",
        "1",
        "--threads",
        "2",
        "-o",
        out.to_str().unwrap(),
        "--json",
        "--turntable",
        "2",
        "--turntable-out",
        anim.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for key in [
        "rays",
        "seconds",
        "rays_per_second",
        "threads",
        "traversal_steps_per_ray",
        "primitive_tests_per_ray",
        "bytes_per_triangle",
    ] {
        assert!(v[key].is_number(), "{key}: {v}");
    }
    assert_eq!(v["threads"], 2);
    assert_eq!(v["primary_rays"], 320);
    assert_eq!(decode(&out).0.width, 20);
    assert_eq!(decode(&anim).2, Some(2));
    let (ok, stdout, stderr) = cbvh(&[
        "render",
        "--gen",
        "robot",
        "--tris",
        "1000",
        "--codec",
        "parry",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        out.to_str().unwrap(),
        "--json",
        "--primary-only",
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["rays"], 64);
    assert!(v["traversal_steps_per_ray"].is_null());
    std::fs::remove_file(&out).ok();
    std::fs::remove_file(&anim).ok();
}

#[test]
fn cli_bad_arguments_give_clear_errors() {
    let out = temp("bad.png");
    let o = out.to_str().unwrap();
    let base = ["render", "--gen", "robot", "--tris", "1000"];
    let run = |extra: &[&str]| {
        let mut a: Vec<&str> = base.to_vec();
        a.extend_from_slice(extra);
        cbvh(&a)
    };
    let (ok, _, e) = run(&["--width", "0", "-o", o]);
    assert!(!ok && e.contains("--width") && e.contains('0'), "{e}");
    let (ok, _, e) = run(&["--height", "0", "-o", o]);
    assert!(!ok && e.contains("--height"), "{e}");
    let (ok, _, e) = run(&["--codec", "zip", "-o", o]);
    assert!(
        !ok && e.contains("zip") && e.contains("plain") && e.contains("parry"),
        "{e}"
    );
    let (ok, _, e) = run(&["--threads", "0", "-o", o]);
    assert!(!ok && e.contains("--threads"), "{e}");
    // Bounded against the machine, before any work.
    let (ok, _, e) = run(&["--threads", "100000", "-o", o]);
    assert!(!ok && e.contains("--threads 100000 is more than"), "{e}");
    let (ok, _, e) = run(&["--elevation", "95", "-o", o]);
    assert!(!ok && e.contains("--elevation 95 must be"), "{e}");
    let (ok, _, e) = run(&["--azimuth", "nan", "-o", o]);
    assert!(!ok && e.contains("--azimuth NaN must be"), "{e}");
    let (ok, _, e) = run(&[]);
    assert!(!ok && e.contains("--output"), "{e}");
    let (ok, _, e) = run(&["-o", "/nonexistent-dir-cbvh/x.png"]);
    assert!(!ok && e.contains("does not exist"), "{e}");
    let (ok, _, e) = run(&["-o", temp("x.jpg").to_str().unwrap()]);
    assert!(!ok && e.contains(".png"), "{e}");
    let (ok, _, e) = run(&[
        "-o",
        o,
        "--turntable",
        "2",
        "--turntable-out",
        temp("x.mp4").to_str().unwrap(),
    ]);
    assert!(!ok && e.contains(".gif"), "{e}");
    let (ok, _, e) = run(&["-o", o, "--turntable-out", temp("x.gif").to_str().unwrap()]);
    assert!(!ok && e.contains("--turntable"), "{e}");
    let missing = temp("missing.off");
    let (ok, _, e) = cbvh(&["render", missing.to_str().unwrap(), "-o", o]);
    assert!(!ok && e.contains("missing.off"), "{e}");
    assert!(!out.exists());
}

/// Issue 33: a turntable keeps its frames in memory until it writes them,
/// so frames × width × height is bounded before any work (3600 frames of
/// 16384² pixels are 2.9 TB: rendering the still alone would take long);
/// and each output's flag is named when its directory is missing, which
/// is not made.
#[test]
fn cli_bounds_the_turntable_memory_and_names_the_output_flags() {
    let base = ["render", "--gen", "robot", "--tris", "1000"];
    let refused = |extra: &[&str]| {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        crate::common::cbvh_refuses_within(&args, 20)
    };
    let out = temp("tt.png");
    let o = out.to_str().unwrap();
    let e = refused(&[
        "--width",
        "16384",
        "--height",
        "16384",
        "--turntable",
        "3600",
        "-o",
        o,
    ]);
    assert!(
        e.contains("--turntable 3600 at --width 16384 --height 16384") && e.contains("memory"),
        "{e}"
    );
    let missing = temp("no-such-dir");
    let inside = missing.join("x.gif");
    let e = refused(&[
        "-o",
        o,
        "--turntable",
        "2",
        "--turntable-out",
        inside.to_str().unwrap(),
    ]);
    assert!(
        e.contains("--turntable-out") && e.contains("does not exist"),
        "{e}"
    );
    let e = refused(&["-o", missing.join("x.png").to_str().unwrap()]);
    assert!(
        e.contains("--output") && e.contains("does not exist"),
        "{e}"
    );
    assert!(!missing.exists() && !out.exists());
}
