//! Clip planes and crop boxes against answers derived independently of the renderer:
//! a clipped ball's silhouette (half a disc), its cut face lit by the plane's normal
//! (Lambert's cosine of a known angle), a crop box that removes half the volume
//! darkening exactly that half of a MIP, clipped matter casting no shadow (`shadows`)
//! and scattering nothing (`path`), bad planes and boxes refused in one line, and a
//! clip change that reuses the classification.

use glint_io::{Samples, Volume};
use glint_render::math::Vec3;
use glint_render::{
    Camera, CameraSpec, ClipPlane, CropBox, Light, Lighting, LightingModel, MaterialOverrides,
    Projection, RenderMode, Renderer, Scene, TransferFunction, View,
};

/// Grid edge of the test volumes (1 mm voxels, world = index).
const N: usize = 48;
/// The volumes' centre, world mm.
const C: f32 = (N - 1) as f32 / 2.0;

/// A volume of `N`^3 1 mm voxels whose value at world point `p` is `f(p)`.
fn volume(f: impl Fn(Vec3) -> f32) -> Volume {
    let mut v = Vec::with_capacity(N * N * N);
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                v.push(f(Vec3::new(i as f32, j as f32, k as f32)));
            }
        }
    }
    Volume::new([N; 3], [1.0; 3], Samples::F32(v)).unwrap()
}

/// 100 inside a ball of radius `r` about the centre, 0 outside, a one-voxel ramp
/// between: flat inside, so its gradient there is zero.
fn ball_value(p: Vec3, r: f32) -> f32 {
    let d = (p - Vec3::new(C, C, C)).length();
    100.0 * (r - d + 0.5).clamp(0.0, 1.0)
}

/// White, opaque above 50.
fn white_tf() -> TransferFunction {
    TransferFunction::from_flat(
        &[-1000.0, 0.0, 40.0, 0.0, 60.0, 1.0, 1000.0, 1.0],
        &[-1000.0, 1.0, 1.0, 1.0, 1000.0, 1.0, 1.0, 1.0],
    )
    .unwrap()
}

/// Diffuse only: a sample shows `max(N·L, 0)` of its colour.
fn lambert() -> MaterialOverrides {
    MaterialOverrides {
        ambient: Some(0.0),
        diffuse: Some(1.0),
        specular: Some(0.0),
        shade: Some(true),
    }
}

/// An orthographic anterior scene of `size`^2 pixels.
fn scene(size: u32) -> Scene {
    Scene {
        size: [size, size],
        camera: CameraSpec {
            view: View::Anterior,
            projection: Projection::Orthographic,
            ..Default::default()
        },
        ..Scene::default()
    }
}

/// Image-plane offsets (mm, right and up) of each pixel's centre from the volume's
/// centre, in `cam` (orthographic) for a `size`^2 image.
fn offsets(cam: &Camera, size: u32) -> impl Fn(u32, u32) -> (f32, f32) + '_ {
    let c = Vec3::new(C, C, C) - cam.eye;
    let (uc, vc) = (c.dot(cam.right), c.dot(cam.up));
    let half = size as f32 / 2.0;
    move |x, y| {
        let u = ((x as f32 + 0.5) / half - 1.0) * cam.half_height;
        let v = (1.0 - (y as f32 + 0.5) / half) * cam.half_height;
        (u - uc, v - vc)
    }
}

fn v64(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// The centre plus `d` mm along `dir`.
fn centre_plus(dir: Vec3, d: f32) -> [f64; 3] {
    v64(Vec3::new(C, C, C) + dir * d)
}

#[test]
fn a_clipped_ball_shows_half_a_disc_and_its_cut_face_lit_by_the_planes_normal() {
    let r = 18.0;
    let vol = volume(|p| ball_value(p, r));
    let size = 96;
    let mut renderer = Renderer::from_source(vol, None).unwrap();
    let base = Scene {
        transfer_function: Some(white_tf()),
        material: lambert(),
        ..scene(size)
    };
    let cam = renderer.camera(&base).unwrap();
    let off = offsets(&cam, size);
    let px = 2.0 * cam.half_height / size as f32;
    for mode in [RenderMode::Iso, RenderMode::Composite] {
        let iso = (mode == RenderMode::Iso).then_some(50.0);
        // Silhouette: the plane through the centre keeping the image's right half.
        let half = Scene {
            mode,
            iso,
            clip: vec![ClipPlane {
                point: centre_plus(cam.right, 0.0),
                normal: v64(cam.right),
            }],
            ..base.clone()
        };
        let img = renderer.render(&half, &|_| {}).unwrap().image;
        let mut checked = 0;
        for y in 0..size {
            for x in 0..size {
                let (du, dv) = off(x, y);
                let rho = (du * du + dv * dv).sqrt();
                if du.abs() < 1.5 * px || (rho - r).abs() < 1.5 * px {
                    continue;
                }
                let a = img.alpha[(y * size + x) as usize];
                if du > 0.0 && rho < r {
                    assert!(a > 0.9, "{mode:?} ({x}, {y}) kept but alpha {a}");
                } else {
                    assert_eq!(a, 0.0, "{mode:?} ({x}, {y}) cut but alpha {a}");
                }
                checked += 1;
            }
        }
        assert!(checked > size * size / 2, "{checked}");

        // Cut face: the plane through the centre, its normal 45 degrees from the view
        // direction, keeps the far, right part; the rays near the centre enter the ball
        // on the plane, where the data is flat. Lit by the headlight along the view,
        // Lambert gives cos 45 degrees of white there (a flat sample would give 1).
        let n = (cam.forward + cam.right).normalize_or_zero();
        let cut = Scene {
            mode,
            iso,
            clip: vec![ClipPlane {
                point: centre_plus(n, 0.0),
                normal: v64(n),
            }],
            ..base.clone()
        };
        let img = renderer.render(&cut, &|_| {}).unwrap().image;
        let expect = std::f32::consts::FRAC_1_SQRT_2;
        let (mut sum, mut count) = (0.0, 0);
        for y in 0..size {
            for x in 0..size {
                let (du, dv) = off(x, y);
                if du.abs() > 5.0 || dv.abs() > 5.0 {
                    continue;
                }
                let v = img.pixel(x, y)[1];
                assert!(
                    (v - expect).abs() < 0.08,
                    "{mode:?} cut face at ({x}, {y}): {v}, Lambert {expect}"
                );
                sum += v;
                count += 1;
            }
        }
        let mean = sum / count as f32;
        assert!(
            count > 20 && (mean - expect).abs() < 0.03,
            "{mode:?} mean {mean}"
        );
    }
}

#[test]
fn a_crop_box_removing_half_the_volume_darkens_exactly_that_half_of_a_mip() {
    // Values varying everywhere (a MIP of every ray is non-zero).
    let vol = volume(|p| 10.0 + ((p.x * 7.0 + p.y * 13.0 + p.z * 29.0) % 17.0));
    let size = 80;
    let mut renderer = Renderer::from_source(vol, None).unwrap();
    let full = Scene {
        mode: RenderMode::Mip,
        ..scene(size)
    };
    let cam = renderer.camera(&full).unwrap();
    let off = offsets(&cam, size);
    let px = 2.0 * cam.half_height / size as f32;
    // The image's right is a world axis in an anterior view: crop away the half of
    // the volume on that side of the centre.
    let r = [cam.right.x, cam.right.y, cam.right.z];
    let a = (0..3)
        .max_by(|&i, &j| r[i].abs().total_cmp(&r[j].abs()))
        .unwrap();
    assert!(r[a].abs() > 0.999, "{r:?}");
    let (mut min, mut max) = ([-1e3; 3], [1e3; 3]);
    if r[a] > 0.0 {
        max[a] = C as f64;
    } else {
        min[a] = C as f64;
    }
    let cropped = Scene {
        crop: Some(CropBox { min, max }),
        ..full.clone()
    };
    let whole = renderer.render(&full, &|_| {}).unwrap().image;
    let half = renderer.render(&cropped, &|_| {}).unwrap().image;
    let (mut kept, mut cut) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let (du, dv) = off(x, y);
            let i = (y * size + x) as usize;
            if du.abs() < 1.5 * px || whole.alpha[i] == 0.0 || dv.abs() > C - 2.0 {
                continue;
            }
            if du < 0.0 {
                assert_eq!(half.rgb[i], whole.rgb[i], "kept ({x}, {y})");
                kept += 1;
            } else {
                assert!(whole.rgb[i][0] > 0.0);
                assert_eq!(
                    (half.rgb[i], half.alpha[i]),
                    ([0.0; 3], 0.0),
                    "cut ({x}, {y})"
                );
                cut += 1;
            }
        }
    }
    assert!(kept > 500 && cut > 500, "{kept} kept, {cut} cut");
}

/// A ball of radius 6 at the centre and, when `plate`, a slab 12..18 mm to the right
/// of it (along `right`): lit from the right, the slab shadows the ball. Without the
/// plate, its corners alone (edges along `right`, far from the ball's light) stay, so
/// both volumes frame the same camera.
fn ball_and_plate(right: Vec3, plate: bool) -> Volume {
    volume(|p| {
        let s = (p - Vec3::new(C, C, C)).dot(right);
        let edge = |x: f32| !(2.0..=(N - 3) as f32).contains(&x);
        let corner = [p.x, p.y, p.z].into_iter().filter(|&x| edge(x)).count() >= 2;
        if (12.0..=18.0).contains(&s) && (plate || corner) {
            100.0
        } else {
            ball_value(p, 6.0)
        }
    })
}

/// The mean green of the pixels within `du` (mm, right of the centre) and `|dv| < 3`.
fn mean_over(
    img: &glint_render::Image,
    off: &dyn Fn(u32, u32) -> (f32, f32),
    du: (f32, f32),
) -> f32 {
    let (mut sum, mut n) = (0.0, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            let (u, v) = off(x, y);
            if (du.0..du.1).contains(&u) && v.abs() < 3.0 {
                sum += img.pixel(x, y)[1];
                n += 1;
            }
        }
    }
    assert!(n > 10, "{n} pixels");
    sum / n as f32
}

/// Renders the ball with and without the plate, the plate clipped or not, under
/// `lighting` in `mode`; returns the ball's mean brightness on its lit side for (ball
/// alone, plate clipped, plate kept), and the plate-only scene clipped.
fn shadow_cases(mode: RenderMode, lighting: Lighting) -> ([f32; 3], glint_render::Image) {
    let size = 64;
    let side = Light {
        azimuth: 90.0,
        elevation: 0.0,
        intensity: 1.0,
    };
    let base = Scene {
        mode,
        iso: (mode == RenderMode::Iso).then_some(50.0),
        transfer_function: Some(white_tf()),
        material: MaterialOverrides {
            ambient: Some(0.2),
            ..lambert()
        },
        lights: vec![side],
        lighting,
        ..scene(size)
    };
    let probe = Renderer::from_source(ball_and_plate(Vec3::new(1.0, 0.0, 0.0), false), None)
        .unwrap()
        .camera(&base)
        .unwrap();
    let right = probe.right;
    assert!(side.direction(&probe).dot(right) > 0.99);
    let clipped = Scene {
        clip: vec![ClipPlane {
            point: centre_plus(right, 9.0),
            normal: v64(-right),
        }],
        ..base.clone()
    };
    // Each volume frames its own camera (the plate widens what is visible): the
    // pixels are chosen by their offsets in mm in each render's camera.
    let lit = (1.0, 5.0);
    let mean = |plate: bool, s: &Scene| {
        let mut r = Renderer::from_source(ball_and_plate(right, plate), None).unwrap();
        let cam = r.camera(s).unwrap();
        let img = r.render(s, &|_| {}).unwrap().image;
        let off = offsets(&cam, size);
        mean_over(&img, &off, lit)
    };
    let means = [
        mean(false, &clipped),
        mean(true, &clipped),
        mean(true, &base),
    ];
    let plate_only = Renderer::from_source(
        volume(|p| {
            let s = (p - Vec3::new(C, C, C)).dot(right);
            if (12.0..=18.0).contains(&s) {
                100.0
            } else {
                0.0
            }
        }),
        None,
    )
    .unwrap()
    .render(&clipped, &|_| {})
    .unwrap()
    .image;
    (means, plate_only)
}

#[test]
fn clipped_matter_casts_no_shadow() {
    let lighting = Lighting {
        model: LightingModel::Shadows,
        ..Lighting::default()
    };
    let ([alone, clipped, kept], plate_only) = shadow_cases(RenderMode::Iso, lighting);
    // The plate kept shadows the ball (the test can fail); clipped, the ball is lit as
    // if the plate were not there.
    assert!(kept < 0.6 * alone, "kept plate {kept}, ball alone {alone}");
    assert!(
        (clipped - alone).abs() < 0.005 * alone,
        "clipped plate {clipped}, ball alone {alone}"
    );
    assert!(plate_only.alpha.iter().all(|&a| a == 0.0));
}

#[test]
fn clipped_matter_scatters_nothing_and_casts_no_shadow_in_path() {
    let lighting = Lighting {
        model: LightingModel::Path,
        spp: Some(24),
        environment: Some(0.0),
        ..Lighting::default()
    };
    let ([alone, clipped, kept], plate_only) = shadow_cases(RenderMode::Composite, lighting);
    assert!(kept < 0.6 * alone, "kept plate {kept}, ball alone {alone}");
    assert!(
        (clipped - alone).abs() < 0.08 * alone,
        "clipped plate {clipped}, ball alone {alone}"
    );
    // Nothing kept: no camera ray meets matter, none scatters.
    assert!(plate_only.alpha.iter().all(|&a| a == 0.0));
    assert!(plate_only.rgb.iter().all(|&c| c == [0.0; 3]));
}

#[test]
fn a_clip_change_reuses_the_classification() {
    let mut renderer = Renderer::from_source(volume(|p| ball_value(p, 15.0)), None).unwrap();
    let base = scene(32);
    let first = renderer.render(&base, &|_| {}).unwrap();
    assert!(first.timings.get("classify") > std::time::Duration::ZERO);
    for x in [C - 5.0, C, C + 5.0] {
        let s = Scene {
            clip: vec![ClipPlane {
                point: [x as f64, 0.0, 0.0],
                normal: [1.0, 0.0, 0.0],
            }],
            crop: Some(CropBox {
                min: [0.0; 3],
                max: [40.0; 3],
            }),
            ..base.clone()
        };
        let r = renderer.render(&s, &|_| {}).unwrap();
        assert_eq!(r.timings.get("classify"), std::time::Duration::ZERO);
        assert_ne!(r.image.rgb, first.image.rgb);
    }
}

#[test]
fn bad_planes_and_boxes_are_refused_in_one_line() {
    let mut renderer = Renderer::from_source(volume(|p| ball_value(p, 15.0)), None).unwrap();
    let plane = |normal| Scene {
        clip: vec![ClipPlane {
            point: [0.0; 3],
            normal,
        }],
        ..scene(16)
    };
    let boxed = |min, max| Scene {
        crop: Some(CropBox { min, max }),
        ..scene(16)
    };
    for (s, what) in [
        (plane([0.0; 3]), "normal is zero"),
        (plane([f64::NAN, 0.0, 1.0]), "finite"),
        (boxed([0.0; 3], [10.0, 10.0, 0.0]), "z from 0 to 0"),
        (
            boxed([5.0, 0.0, 0.0], [1.0, 10.0, 10.0]),
            "empty or inverted",
        ),
    ] {
        let e = renderer.render(&s, &|_| {}).unwrap_err().to_string();
        assert!(e.contains(what) && !e.contains('\n'), "{e}");
    }
    // Through JSON too: an inverted box in a scene file.
    let json = r#"{"crop": {"min": [0, 0, 0], "max": [-1, 1, 1]}, "size": [16, 16]}"#;
    let s = Scene::from_json(json).unwrap();
    let e = renderer.render(&s, &|_| {}).unwrap_err().to_string();
    assert!(e.contains("crop box: x from 0 to -1"), "{e}");
}

#[test]
fn scenes_without_a_clip_serialise_as_before_and_clips_round_trip() {
    let json = Scene::default().to_json().unwrap();
    assert!(!json.contains("clip") && !json.contains("crop"), "{json}");
    let s = Scene {
        clip: vec![ClipPlane {
            point: [1.0, 2.0, 3.0],
            normal: [0.0, -1.0, 0.0],
        }],
        crop: Some(CropBox {
            min: [-5.0; 3],
            max: [5.0; 3],
        }),
        ..Scene::default()
    };
    let back = Scene::from_json(&s.to_json().unwrap()).unwrap();
    assert_eq!(back, s);
    // A patch sets and removes them, as the viewer and Python send them.
    let patch = serde_json::json!({"clip": null, "crop": {"min": [0, 0, 0], "max": [1, 2, 3]}});
    let p = s.patch(patch.as_object().unwrap()).unwrap();
    assert!(p.clip.is_empty());
    assert_eq!(p.crop.unwrap().max, [1.0, 2.0, 3.0]);
}
