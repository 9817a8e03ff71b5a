//! Picking against analytic phantoms: a ball whose value is its depth below the
//! surface (`R - |p - c|`, mm), so the point each ray should show is the ray's
//! analytic entry into the ball (composite, iso) or its closest approach to the
//! centre (MIP); the values and labels at the point; meshes in front of and behind
//! the ball; points off the image.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glint_io::{nifti, Endian, Mesh, Samples, Volume};
use glint_render::{
    Camera, CameraSpec, ClipPlane, CropBox, Input, LabelSpec, LabelsAs, MeshSpec, Pick,
    PickedObject, Projection, RenderError, RenderMode, Renderer, Sampling, Scene, TransferFunction,
    View,
};

/// Grid edge of the ball's volume, voxels.
const N: usize = 40;
/// Voxel size, mm (anisotropic, so voxel and world coordinates differ).
const SPACING: [f64; 3] = [0.9, 1.0, 1.2];
/// The ball's radius, mm.
const R: f64 = 14.0;

/// Centre of the grid in world mm.
fn centre() -> [f64; 3] {
    SPACING.map(|s| s * (N - 1) as f64 / 2.0)
}

/// The analytic value of voxel `ijk`: its depth below the ball's surface, mm.
fn depth_below(ijk: [usize; 3]) -> f64 {
    let c = centre();
    R - (0..3)
        .map(|a| (ijk[a] as f64 * SPACING[a] - c[a]).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn ball() -> Volume {
    let mut values = Vec::with_capacity(N * N * N);
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                values.push(depth_below([i, j, k]) as f32);
            }
        }
    }
    Volume::new([N; 3], SPACING, Samples::F32(values)).unwrap()
}

/// Half the smallest voxel edge: the tolerance the issue sets for a front point.
fn half_voxel() -> f64 {
    0.5 * SPACING.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Opaque at once from 0.05 mm below the surface: a composite pick at any threshold
/// lands on the surface.
fn hard_tf() -> TransferFunction {
    TransferFunction::from_flat(
        &[-100.0, 0.0, 0.0, 0.0, 0.05, 1.0, 100.0, 1.0],
        &[-100.0, 1.0, 1.0, 1.0, 100.0, 1.0, 1.0, 1.0],
    )
    .unwrap()
}

fn scene(mode: RenderMode, view: View, projection: Projection) -> Scene {
    Scene {
        mode,
        iso: (mode == RenderMode::Iso).then_some(0.0),
        transfer_function: Some(hard_tf()),
        size: [48, 40],
        camera: CameraSpec {
            view,
            azimuth: 20.0,
            elevation: 15.0,
            projection,
            ..CameraSpec::default()
        },
        ..Scene::default()
    }
}

fn renderer() -> Renderer {
    Renderer::from_source(ball(), None).unwrap()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    dot(sub(a, b), sub(a, b)).sqrt()
}

/// The world ray of image point `(x, y)` (pixels from the top-left corner).
fn ray(camera: &Camera, scene: &Scene, x: f64, y: f64) -> ([f64; 3], [f64; 3]) {
    let [w, h] = scene.size;
    let (o, d) = camera.ray((x - 0.5) as f32, (y - 0.5) as f32, w, h);
    (
        [o.x, o.y, o.z].map(f64::from),
        [d.x, d.y, d.z].map(f64::from),
    )
}

/// The image points of a grid over the image, off pixel centres too.
fn points(scene: &Scene) -> Vec<(f64, f64)> {
    let [w, h] = scene.size;
    let mut out = Vec::new();
    for j in 0..h / 3 {
        for i in 0..w / 3 {
            out.push((3.0 * i as f64 + 0.5, 3.0 * j as f64 + 1.25));
        }
    }
    out
}

/// What an image point should show: `Some(Some(entry))` where its ray enters the
/// ball, `Some(None)` where it misses, `None` where it grazes the silhouette (either
/// answer is right).
type Expected = Option<Option<[f64; 3]>>;

/// Per image point: the ray's entry into the ball (grazing: within `margin` mm of the
/// silhouette).
fn entries(camera: &Camera, scene: &Scene, margin: f64) -> Vec<((f64, f64), Expected)> {
    let c = centre();
    points(scene)
        .into_iter()
        .map(|(x, y)| {
            let (o, d) = ray(camera, scene, x, y);
            let oc = sub(c, o);
            let along = dot(oc, d);
            let miss = (dot(oc, oc) - along * along).max(0.0).sqrt();
            let expect = if miss < R - margin {
                let back = (R * R - miss * miss).sqrt();
                let t = along - back;
                Some(Some([0, 1, 2].map(|a| o[a] + d[a] * t)))
            } else if miss > R + margin {
                Some(None)
            } else {
                None
            };
            ((x, y), expect)
        })
        .collect()
}

fn check_front_points(mode: RenderMode, sampling: Sampling, threshold: f32) {
    for (view, projection) in [
        (View::Anterior, Projection::Perspective),
        (View::Left, Projection::Orthographic),
    ] {
        let mut scene = scene(mode, view, projection);
        scene.sampling = sampling;
        let mut r = renderer();
        let camera = r.camera(&scene).unwrap();
        let mut hits = 0;
        for ((x, y), expect) in entries(&camera, &scene, 1.0) {
            let Some(expect) = expect else { continue };
            let pick = r.pick_with(&scene, x, y, threshold).unwrap();
            match (expect, pick) {
                (None, None) => {}
                (Some(p), Some(pick)) => {
                    hits += 1;
                    assert_eq!(pick.object, PickedObject::Volume);
                    let e = dist(pick.world_mm, p);
                    assert!(
                        e < half_voxel(),
                        "{mode:?} {sampling:?} {view:?} ({x}, {y}): {:?} is {e} mm from the entry {p:?}",
                        pick.world_mm
                    );
                    // The depth is the distance along the ray.
                    let (o, _) = ray(&camera, &scene, x, y);
                    let along = match projection {
                        Projection::Perspective => dist(o, pick.world_mm),
                        Projection::Orthographic => {
                            let f = camera.forward;
                            dot(sub(pick.world_mm, o), [f.x, f.y, f.z].map(f64::from))
                        }
                    };
                    assert!((along - pick.depth_mm).abs() < 1e-3, "{along} {pick:?}");
                }
                (expect, pick) => {
                    panic!("{mode:?} {view:?} ({x}, {y}): expected {expect:?}, picked {pick:?}")
                }
            }
        }
        assert!(
            hits > 20,
            "{mode:?} {view:?}: only {hits} rays met the ball"
        );
    }
}

#[test]
fn composite_picks_land_on_the_balls_front_within_half_a_voxel() {
    check_front_points(RenderMode::Composite, Sampling::Point, 0.5);
    check_front_points(RenderMode::Composite, Sampling::PreIntegrated, 0.5);
    check_front_points(RenderMode::Composite, Sampling::Point, 0.95);
}

#[test]
fn iso_picks_land_on_the_balls_front_within_half_a_voxel() {
    check_front_points(RenderMode::Iso, Sampling::Point, 0.5);
}

#[test]
fn mip_picks_land_on_the_rays_closest_approach_to_the_centre() {
    let scene = scene(RenderMode::Mip, View::Anterior, Projection::Perspective);
    let mut r = renderer();
    let camera = r.camera(&scene).unwrap();
    let c = centre();
    let mut checked = 0;
    for ((x, y), expect) in entries(&camera, &scene, 1.0) {
        if !matches!(expect, Some(Some(_))) {
            continue;
        }
        let (o, d) = ray(&camera, &scene, x, y);
        let t = dot(sub(c, o), d);
        let closest = [0, 1, 2].map(|a| o[a] + d[a] * t);
        let pick = r
            .pick(&scene, x, y)
            .unwrap()
            .expect("the ray meets the ball");
        assert_eq!(pick.object, PickedObject::Volume);
        let e = dist(pick.world_mm, closest);
        assert!(e < half_voxel(), "({x}, {y}): {e} mm from {closest:?}");
        checked += 1;
    }
    assert!(checked > 20);
}

#[test]
fn picks_agree_with_the_frames_opacity_at_pixel_centres() {
    // A soft ball: opacity grows with depth, so pixels near the silhouette stay
    // below the threshold; a pick finds a point exactly where the frame's
    // accumulated opacity reaches it.
    let tf =
        TransferFunction::from_flat(&[0.0, 0.0, R, 0.3], &[0.0, 1.0, 1.0, 1.0, R, 1.0, 1.0, 1.0])
            .unwrap();
    let scene = Scene {
        transfer_function: Some(tf),
        size: [32, 32],
        ..Scene::default()
    };
    let mut r = renderer();
    let image = r.render(&scene, &|_| {}).unwrap().image;
    let (mut some, mut none) = (0, 0);
    for j in 0..32u32 {
        for i in 0..32u32 {
            let alpha = image.alpha[(j * 32 + i) as usize];
            if (alpha - 0.5).abs() < 1e-3 {
                continue;
            }
            let pick = r
                .pick(&scene, f64::from(i) + 0.5, f64::from(j) + 0.5)
                .unwrap();
            assert_eq!(
                pick.is_some(),
                alpha > 0.5,
                "pixel ({i}, {j}) alpha {alpha}"
            );
            if alpha > 0.5 {
                some += 1;
            } else {
                none += 1;
            }
        }
    }
    assert!(some > 50 && none > 50, "{some} hit, {none} missed");
}

#[test]
fn a_pick_reports_the_voxel_and_its_value() {
    let scene = scene(RenderMode::Iso, View::Anterior, Projection::Perspective);
    let mut r = renderer();
    let pick: Pick = r.pick(&scene, 24.0, 20.0).unwrap().unwrap();
    let voxel = pick.voxel.unwrap();
    for a in 0..3 {
        assert!(
            (voxel[a] * SPACING[a] - pick.world_mm[a]).abs() < 1e-3,
            "{pick:?}"
        );
    }
    let nearest = pick.voxel_nearest.unwrap();
    for a in 0..3 {
        assert!((nearest[a] as f64 - voxel[a]).abs() <= 0.5);
    }
    // The stored value of the nearest voxel, and the reconstruction at the iso
    // surface, in the volume's units (mm of depth here).
    let value = pick.value.unwrap();
    assert!((value - depth_below(nearest)).abs() < 1e-4, "{pick:?}");
    assert!(pick.interpolated.unwrap().abs() < 0.05, "{pick:?}");
    assert_eq!(pick.label, None);
    // The JSON front ends print.
    let json = serde_json::to_value(&pick).unwrap();
    assert_eq!(json["object"]["kind"], "volume");
    assert_eq!(json["voxel_nearest"][0], nearest[0]);
}

#[test]
fn points_off_the_image_and_bad_thresholds_are_refused_in_one_line() {
    let scene = scene(
        RenderMode::Composite,
        View::Anterior,
        Projection::Perspective,
    );
    let mut r = renderer();
    for (x, y) in [(-0.1, 3.0), (48.0, 3.0), (3.0, 40.0), (f64::NAN, 1.0)] {
        let e = r.pick(&scene, x, y).unwrap_err();
        assert!(
            matches!(
                e,
                RenderError::OffImage {
                    width: 48,
                    height: 40,
                    ..
                }
            ),
            "{e:?}"
        );
        let line = e.to_string();
        assert!(
            line.contains("off the 48x40 image") && !line.contains('\n'),
            "{line}"
        );
    }
    assert!(r.pick(&scene, 47.99, 39.99).is_ok());
    for t in [0.0, 1.0, f32::NAN] {
        let e = r.pick_with(&scene, 24.0, 20.0, t).unwrap_err();
        assert!(e.to_string().contains("threshold"), "{e}");
    }
}

/// A square in the plane `axis = at` (world mm) over `u` x `v` along the next two
/// axes in cyclic order (for y: z, then x), written as an OBJ file.
fn square(dir: &Path, name: &str, axis: usize, at: f32, u: [f32; 2], v: [f32; 2]) -> PathBuf {
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |p: f32, q: f32| {
        let mut c = [0.0f32; 3];
        (c[axis], c[a], c[b]) = (at, p, q);
        c
    };
    let mesh = Mesh {
        positions: vec![
            corner(u[0], v[0]),
            corner(u[1], v[0]),
            corner(u[1], v[1]),
            corner(u[0], v[1]),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        normals: None,
        scalars: None,
    };
    let path = dir.join(name);
    glint_io::mesh::write_obj(&path, &mesh).unwrap();
    path
}

#[test]
fn meshes_are_picked_where_they_are_nearer_than_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    let c = centre().map(|x| x as f32);
    let rad = R as f32;
    // Seen from the front (anterior, +y): a square in front of the ball's right
    // half (x > centre), and one behind all of it.
    let front = square(
        dir.path(),
        "front.obj",
        1,
        c[1] + rad + 4.0,
        [c[2] - 30.0, c[2] + 30.0],
        [c[0] + 2.0, c[0] + 30.0],
    );
    let back = square(
        dir.path(),
        "back.obj",
        1,
        c[1] - rad - 4.0,
        [c[0] - 40.0, c[0] + 40.0],
        [c[2] - 40.0, c[2] + 40.0],
    );
    let scene = Scene {
        meshes: vec![MeshSpec::new(&front), MeshSpec::new(&back)],
        transfer_function: Some(hard_tf()),
        size: [64, 64],
        camera: CameraSpec {
            view: View::Anterior,
            projection: Projection::Orthographic,
            ..CameraSpec::default()
        },
        ..Scene::default()
    };
    let mut r = renderer();
    let camera = r.camera(&scene).unwrap();
    let mut seen = BTreeMap::new();
    for j in 0..16 {
        for i in 0..16 {
            let (x, y) = (4.0 * i as f64 + 2.0, 4.0 * j as f64 + 2.0);
            let (o, d) = ray(&camera, &scene, x, y);
            let Some(pick) = r.pick(&scene, x, y).unwrap() else {
                continue;
            };
            // Where the ray crosses the planes, and whether it meets the ball.
            let plane = |at: f32| {
                let t = (f64::from(at) - o[1]) / d[1];
                [0, 1, 2].map(|a| o[a] + d[a] * t)
            };
            let on_front = plane(c[1] + rad + 4.0);
            let in_front = on_front[0] > f64::from(c[0]) + 2.0;
            let oc = sub(centre(), o);
            let along = dot(oc, d);
            let miss = (dot(oc, oc) - along * along).sqrt();
            let kind = match &pick.object {
                PickedObject::Mesh { index: 0, path } => {
                    assert_eq!(path, &front);
                    assert!(in_front, "({x}, {y}) picked the front square off it");
                    assert!(dist(pick.world_mm, on_front) < 1e-2);
                    "front"
                }
                PickedObject::Mesh { index: 1, .. } => {
                    assert!(
                        !in_front && miss > R - 0.5,
                        "({x}, {y}): the back square through the ball"
                    );
                    assert!(dist(pick.world_mm, plane(c[1] - rad - 4.0)) < 1e-2);
                    "back"
                }
                PickedObject::Volume => {
                    assert!(
                        !in_front && miss < R + 0.5,
                        "({x}, {y}): the ball behind the square"
                    );
                    "ball"
                }
                other => panic!("({x}, {y}): {other:?}"),
            };
            *seen.entry(kind).or_insert(0) += 1;
        }
    }
    assert!(seen.len() == 3 && seen.values().all(|&n| n > 5), "{seen:?}");
}

/// The ball's voxels labelled by side: 17 (FreeSurfer's Left-Hippocampus) where x is
/// below the centre, 18 (Left-Amygdala) above, 0 outside, on the ball's grid.
fn halves(dir: &Path) -> PathBuf {
    let mut values = Vec::with_capacity(N * N * N);
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                let inside = depth_below([i, j, k]) >= -1.0;
                values.push(match (inside, i < N / 2) {
                    (false, _) => 0u8,
                    (true, true) => 17,
                    (true, false) => 18,
                });
            }
        }
    }
    let vol = Volume::new([N; 3], SPACING, Samples::U8(values)).unwrap();
    let path = dir.join("aseg.nii");
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    path
}

#[test]
fn picks_name_the_label_at_the_point() {
    let dir = tempfile::tempdir().unwrap();
    let path = halves(dir.path());
    // The labels as an invisible label volume: the ball is picked, the labels read.
    let mut labels = LabelSpec::new(&path);
    labels.render_as = LabelsAs::Volume;
    labels.opacity = [("17".to_string(), 0.0), ("18".to_string(), 0.0)].into();
    let mut scene = scene(RenderMode::Iso, View::Anterior, Projection::Orthographic);
    scene.labels = Some(labels);
    (scene.camera.azimuth, scene.camera.elevation) = (0.0, 0.0);
    let mut r = renderer();
    let [w, h] = scene.size;
    let (y, cx) = (f64::from(h) / 2.0, f64::from(w) / 2.0);
    // Seen from the front, the image's left is the patient's right (+x, RAS).
    for (x, id, name) in [
        (cx + 6.0, 17, "Left-Hippocampus"),
        (cx - 6.0, 18, "Left-Amygdala"),
    ] {
        let pick = r.pick(&scene, x, y).unwrap().unwrap();
        assert_eq!(pick.object, PickedObject::Volume);
        let label = pick
            .label
            .clone()
            .unwrap_or_else(|| panic!("no label at {pick:?}"));
        assert_eq!((label.id, label.name.as_str()), (id, name), "{pick:?}");
    }
    // Label surfaces alone: the surface is picked and names its label.
    let mut only = LabelSpec::new(&path);
    only.show = vec!["18".into()];
    let surfaces = Scene {
        input: Input::None,
        labels: Some(only),
        size: [32, 32],
        ..Scene::default()
    };
    let mut r = Renderer::open(&surfaces, &glint_render::ReadOptions::default()).unwrap();
    let pick = r.pick(&surfaces, 16.0, 16.0).unwrap().unwrap();
    assert_eq!(pick.object, PickedObject::LabelSurface { label: 18 });
    assert_eq!(pick.label.unwrap().name, "Left-Amygdala");
    assert_eq!(pick.voxel, None, "no volume");
}

#[test]
fn picked_points_project_back_to_where_they_were_picked() {
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let scene = scene(RenderMode::Iso, View::Left, projection);
        let mut r = renderer();
        let resolved = r.render(&scene, &|_| {}).unwrap().scene;
        for (x, y) in [(24.0, 20.0), (17.3, 25.9), (30.5, 14.25)] {
            let pick = r.pick(&scene, x, y).unwrap().unwrap();
            let [px, py] = glint_render::image_point(&resolved, pick.world_mm).unwrap();
            assert!(
                (px - x).abs() < 0.01 && (py - y).abs() < 0.01,
                "{projection:?} ({x}, {y}) projects to ({px}, {py})"
            );
        }
    }
    // A scene never rendered has no camera to project with.
    assert_eq!(glint_render::image_point(&Scene::default(), [0.0; 3]), None);
}

/// A clip plane through the ball's centre facing away from the camera: a pick lands
/// on the cut face (the plane), not on the clipped front; a crop box that keeps
/// nothing of the ball leaves nothing to pick. Picks are cut as the frame's rays are.
#[test]
fn picks_respect_clip_planes_and_crop_boxes() {
    for mode in [RenderMode::Composite, RenderMode::Iso] {
        let mut scene = scene(mode, View::Anterior, Projection::Orthographic);
        let mut r = renderer();
        let camera = r.camera(&scene).unwrap();
        let f = camera.forward;
        let forward = [f.x, f.y, f.z].map(f64::from);
        let (x, y) = (24.0, 20.0);
        let front = r.pick(&scene, x, y).unwrap().unwrap();
        scene.clip = vec![ClipPlane {
            point: centre(),
            normal: forward,
        }];
        let cut = r.pick(&scene, x, y).unwrap().unwrap();
        let off_plane = dot(sub(cut.world_mm, centre()), forward);
        assert!(
            off_plane.abs() < half_voxel(),
            "{mode:?}: {cut:?} is {off_plane} mm off the plane"
        );
        assert!(cut.depth_mm > front.depth_mm + 0.5 * R, "{front:?} {cut:?}");
        scene.clip.clear();
        let c = centre();
        scene.crop = Some(CropBox {
            min: [c[0] + 2.0 * R, c[1], c[2]],
            max: [c[0] + 3.0 * R, c[1] + R, c[2] + R],
        });
        assert_eq!(r.pick(&scene, x, y).unwrap(), None, "{mode:?}");
    }
}
