//! Odd but valid volumes (found by mutating NIfTI headers, issue 33) render the
//! object: a float volume with a few voxels at 1e29, a strongly sheared affine.

use glint_io::{Samples, Volume};
use glint_render::{Input, Renderer, Scene};

/// A ball of radius 15 voxels, value 1000, in a 48^3 float grid.
fn ball() -> Volume {
    let n = 48;
    let v = (0..n * n * n)
        .map(|i| {
            let p = [i % n, i / n % n, i / (n * n)].map(|x| x as f32 - 23.5);
            if p.iter().map(|x| x * x).sum::<f32>() < 225.0 {
                1000.0
            } else {
                0.0
            }
        })
        .collect();
    Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap()
}

/// Pixels with opacity above one half, and the box they span (x0, y0, x1, y1).
fn covered(volume: &Volume) -> (usize, [u32; 4]) {
    let scene = Scene {
        input: Input::Path("ball.nii".into()),
        preset: Some("mr-default".into()),
        size: [96, 96],
        ..Scene::default()
    };
    let image = Renderer::from_source(volume.clone(), None)
        .unwrap()
        .render(&scene, &|_| {})
        .unwrap()
        .image;
    let mut bbox = [u32::MAX, u32::MAX, 0, 0];
    let mut n = 0;
    for y in 0..image.height {
        for x in 0..image.width {
            if image.alpha[(y * image.width + x) as usize] > 0.5 {
                n += 1;
                bbox = [
                    bbox[0].min(x),
                    bbox[1].min(y),
                    bbox[2].max(x),
                    bbox[3].max(y),
                ];
            }
        }
    }
    (n, bbox)
}

#[test]
fn a_few_voxels_at_1e29_do_not_hide_the_object() {
    let plain = covered(&ball()).0;
    let mut odd = ball();
    if let Samples::F32(v) = &mut odd.samples {
        for k in 0..5 {
            v[k * 997] = 1e29;
        }
    }
    let (n, _) = covered(&odd);
    // The ball covers about pi 15^2 / 48^2 of a framed image; the outliers sit in its
    // corners and are few: within a quarter of the plain ball's coverage.
    assert!(plain > 2000, "{plain}");
    assert!(
        (n as f64 - plain as f64).abs() < 0.25 * plain as f64,
        "{n} vs {plain}"
    );
}

#[test]
fn a_strongly_sheared_grid_is_framed_on_the_object() {
    let mut sheared = ball();
    sheared.affine[0][1] = 2.5;
    sheared.affine[0][2] = 2.5;
    sheared.affine[1][2] = 2.5;
    let (n, b) = covered(&sheared);
    assert!(n > 300, "{n} pixels");
    // The object reaches across most of the image along its long side.
    let span = (b[2] - b[0]).max(b[3] - b[1]);
    assert!(span > 70, "{b:?}");
}

#[test]
fn nan_and_1e30_voxels_give_finite_features_and_denoised_path_images() {
    use glint_render::{Denoise, Lighting, LightingModel};
    let mut odd = ball();
    if let Samples::F32(v) = &mut odd.samples {
        let n = v.len();
        for k in 0..200 {
            v[(k * 7919) % n] = if k % 2 == 0 { f32::NAN } else { 1e30 };
        }
    }
    let mut renderer = Renderer::from_source(odd, None).unwrap();
    for denoise in [Denoise::Atrous, Denoise::Auto] {
        let scene = Scene {
            input: Input::Path("ball.nii".into()),
            preset: Some("mr-default".into()),
            size: [40, 40],
            lighting: Lighting {
                model: LightingModel::Path,
                spp: Some(1),
                denoise: Some(denoise),
                ..Lighting::default()
            },
            ..Scene::default()
        };
        let image = renderer.render(&scene, &|_| {}).unwrap().image;
        assert!(
            image.rgb.iter().flatten().all(|v| v.is_finite()),
            "{denoise:?}: a value that is not finite"
        );
        assert!(
            image.alpha.iter().any(|&a| a > 0.5),
            "the ball is not drawn"
        );
    }
    // The feature buffers themselves are finite, with the ball hit.
    let resolved = renderer
        .resolve(&Scene {
            input: Input::Path("ball.nii".into()),
            preset: Some("mr-default".into()),
            size: [40, 40],
            ..Scene::default()
        })
        .unwrap();
    let glint_render::Plan::Volume {
        tf,
        classify,
        frame,
        ..
    } = resolved.plan
    else {
        panic!("a volume plan");
    };
    let (class, _) = renderer.classification(&tf, &classify).unwrap();
    let f = class.path_features(&resolved.shader, &frame, None).unwrap();
    let values = f.albedo.iter().chain(&f.normal).flatten().chain(&f.depth);
    assert!(values.into_iter().all(|v| v.is_finite()));
    assert!((0..f.depth.len()).any(|i| f.hit(i)), "no first hit");
}
