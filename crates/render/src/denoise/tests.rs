use glint_core::{Image, RenderStats};
use glint_volume::{LightingModel, PathFeatures, Phantom};

use super::*;
use crate::{Input, Lighting, ReadOptions, Renderer, Scene};

/// Features of a `w`x`h` frame: a tilted plane hit everywhere but a band of misses,
/// two albedos and normals, so every weight varies.
fn features(w: u32, h: u32) -> PathFeatures {
    let n = (w * h) as usize;
    let mut f = PathFeatures {
        width: w,
        height: h,
        albedo: vec![[0.0; 3]; n],
        normal: vec![[0.0; 3]; n],
        depth: vec![-1.0; n],
    };
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if y % 7 == 3 {
                continue;
            }
            let left = x < w / 2;
            f.albedo[i] = if left {
                [0.9, 0.8, 0.7]
            } else {
                [0.3, 0.5, 0.2]
            };
            f.normal[i] = if left {
                [0.0, 0.0, 1.0]
            } else {
                [0.6, 0.0, 0.8]
            };
            f.depth[i] = 100.0 + 0.3 * x as f32 + 0.1 * y as f32;
        }
    }
    f
}

/// A `w`x`h` image of `rgb(i)`.
fn image(w: u32, h: u32, rgb: impl Fn(usize) -> [f32; 3]) -> Image {
    let n = (w * h) as usize;
    Image {
        width: w,
        height: h,
        rgb: (0..n).map(rgb).collect(),
        alpha: vec![1.0; n],
        stats: RenderStats::default(),
    }
}

/// A noisy value in 0..2 per pixel and channel (a fixed integer hash).
fn noise(i: usize, c: usize) -> f32 {
    let mut x = (i as u64 * 3 + c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 32;
    (x % 2000) as f32 / 1000.0
}

#[test]
fn the_filter_keeps_a_constant_image_bit_for_bit() {
    let (w, h) = (40, 30);
    let f = PathFeatures {
        albedo: vec![[0.37, 0.52, 0.81]; 1200],
        normal: vec![[0.0, 0.6, 0.8]; 1200],
        depth: vec![123.4; 1200],
        ..features(w, h)
    };
    let flat = image(w, h, |_| [0.3, 0.7, 1.9]);
    // Variance unknown (one sample: the spatial estimate) and given.
    for variance in [vec![], vec![0.01; 1200]] {
        let out = atrous(&flat, &f, &variance, &AtrousSettings::default());
        assert_eq!(out, flat);
    }
}

#[test]
fn the_filter_keeps_an_edge_the_variance_calls_signal_and_smooths_noise() {
    // One surface (constant features), radiance stepping from 1 to 2 halfway.
    let (w, h) = (32, 24);
    let n = (w * h) as usize;
    let f = PathFeatures {
        albedo: vec![[0.5; 3]; n],
        normal: vec![[0.0, 0.0, 1.0]; n],
        depth: vec![50.0; n],
        ..features(w, h)
    };
    let step = |i: usize| {
        if i % w as usize >= w as usize / 2 {
            2.0
        } else {
            1.0
        }
    };
    let edge = image(w, h, |i| [step(i); 3]);
    // Converged samples (standard error 1e-3): the step is 1000 errors high, kept.
    let kept = atrous(&edge, &f, &vec![1e-6; n], &AtrousSettings::default());
    let moved = (kept.rgb.iter().zip(&edge.rgb))
        .map(|(a, b)| (a[0] - b[0]).abs())
        .fold(0.0f32, f32::max);
    assert!(moved < 1e-3, "a converged edge moved by {moved}");
    // A standard error of 1 (one noisy sample): the step is noise, smoothed across.
    let smoothed = atrous(&edge, &f, &vec![1.0; n], &AtrousSettings::default());
    let (l, r) = (w as usize / 2 - 1, w as usize / 2);
    let row = 12 * w as usize;
    let gap = smoothed.rgb[row + r][0] - smoothed.rgb[row + l][0];
    assert!(gap < 0.5, "a noisy step kept {gap} of 1");
    // Noise of a known variance is reduced: the filtered pixels scatter less.
    let noisy = image(w, h, |i| [1.0 + noise(i, 0) - 1.0; 3]);
    let spread = |im: &Image| {
        let m = im.rgb.iter().map(|c| c[0]).sum::<f32>() / n as f32;
        im.rgb.iter().map(|c| (c[0] - m).powi(2)).sum::<f32>() / n as f32
    };
    let var = spread(&noisy);
    let out = atrous(&noisy, &f, &vec![var; n], &AtrousSettings::default());
    assert!(
        spread(&out) < 0.1 * var,
        "variance {var} -> {}",
        spread(&out)
    );
}

#[test]
fn the_filter_is_the_same_bit_for_bit_on_any_thread_count() {
    let (w, h) = (48, 40);
    let f = features(w, h);
    let noisy = image(w, h, |i| [0, 1, 2].map(|c| noise(i, c)));
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| atrous(&noisy, &f, &[], &AtrousSettings::default()))
    };
    let one = run(1);
    assert_ne!(one, noisy, "the filter changed nothing");
    for threads in [2, 3, 7] {
        let many = run(threads);
        let bits = |im: &Image| {
            im.rgb
                .iter()
                .flatten()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&one), bits(&many), "{threads} threads");
    }
}

#[test]
fn the_filter_gives_finite_values_for_nan_and_huge_input() {
    let (w, h) = (16, 16);
    let f = features(w, h);
    let odd = image(w, h, |i| match i % 4 {
        0 => [f32::NAN, 1.0, 1.0],
        1 => [1e30, f32::INFINITY, 0.5],
        2 => [f32::NEG_INFINITY, 0.2, 0.1],
        _ => [0.5, 0.5, 0.5],
    });
    let out = atrous(&odd, &f, &[f32::NAN; 256], &AtrousSettings::default());
    assert!(out.rgb.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
}

/// The Shepp-Logan phantom in `path`, 48x48, `spp` samples, seed `seed`, denoised by
/// `denoise`.
fn phantom(spp: u32, seed: u64, denoise: Option<Denoise>) -> Scene {
    Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 48,
        },
        size: [48, 48],
        lighting: Lighting {
            model: LightingModel::Path,
            spp: Some(spp),
            seed: Some(seed),
            denoise,
            ..Lighting::default()
        },
        ..Scene::default()
    }
}

fn mse(a: &Image, b: &Image) -> f64 {
    let sum: f64 = a
        .rgb
        .iter()
        .flatten()
        .zip(b.rgb.iter().flatten())
        .map(|(x, y)| f64::from(x - y).powi(2))
        .sum();
    sum / (3 * a.rgb.len()) as f64
}

#[test]
fn a_denoised_low_spp_image_is_closer_to_the_converged_one_than_the_raw_one() {
    let reference = phantom(256, 99, None);
    let mut r = Renderer::open(&reference, &ReadOptions::default()).unwrap();
    let truth = r.render(&reference, &|_| {}).unwrap().image;
    let raw = r.render(&phantom(2, 1, None), &|_| {}).unwrap();
    let filtered = r
        .render(&phantom(2, 1, Some(Denoise::Atrous)), &|_| {})
        .unwrap();
    // Denoising kept the samples: the same scene's raw image is continued, not redone.
    assert_eq!(r.path_samples(), 2);
    assert_eq!(filtered.scene.lighting.denoise, Some(Denoise::Atrous));
    let (before, after) = (mse(&raw.image, &truth), mse(&filtered.image, &truth));
    assert!(
        after < 0.5 * before,
        "MSE to the 256-spp image: raw {before}, atrous {after}"
    );
    // Denoising again gives the same image bit for bit.
    let again = r
        .render(&phantom(2, 1, Some(Denoise::Atrous)), &|_| {})
        .unwrap();
    assert_eq!(again.image, filtered.image);
}

#[test]
fn oidn_without_its_library_is_one_line_naming_it_and_auto_falls_back() {
    // The search: nothing loads from paths that do not hold the library.
    let nowhere = [std::path::PathBuf::from(
        "/nonexistent/libOpenImageDenoise.so.2",
    )];
    assert!(!super::oidn::loads_from(&nowhere));
    let line = no_oidn();
    assert!(!line.contains('\n'), "{line}");
    for part in [
        "libOpenImageDenoise",
        "$OIDN_DIR",
        "scripts/fetch-oidn",
        "--denoise atrous",
    ] {
        assert!(line.contains(part), "{line}");
    }
    let scene = phantom(1, 0, Some(Denoise::Oidn));
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let auto = r.render(&phantom(1, 0, Some(Denoise::Auto)), &|_| {});
    assert!(auto.is_ok());
    match r.render(&scene, &|_| {}) {
        Ok(_) => assert!(has_oidn(), "oidn rendered without its library"),
        Err(e) => {
            assert!(!has_oidn(), "{e}");
            assert!(e.to_string().ends_with(&line), "{e}");
        }
    }
    assert_eq!("atrous".parse::<Denoise>().unwrap(), Denoise::Atrous);
    assert!("fast".parse::<Denoise>().is_err());
}

/// OIDN on a 2-spp `path` frame of the phantom (where its library loads: CI fetches
/// it, and a missing one fails there): much closer to the 256-spp image than the raw
/// frame, every value finite, and the same image again at the same thread count.
#[test]
fn oidn_denoises_a_path_frame_toward_the_converged_image() {
    if !has_oidn() {
        glint_testkit::missing(&format!("Intel Open Image Denoise: {}", no_oidn()));
        return;
    }
    glint_testkit::ran("Intel Open Image Denoise (--denoise oidn)");
    let reference = phantom(256, 1, None);
    let mut r = Renderer::open(&reference, &ReadOptions::default()).unwrap();
    let truth = r.render(&reference, &|_| {}).unwrap().image;
    let raw = r.render(&phantom(2, 1, None), &|_| {}).unwrap();
    let oidn = r
        .render(&phantom(2, 1, Some(Denoise::Oidn)), &|_| {})
        .unwrap();
    assert!(oidn.image.rgb.iter().flatten().all(|v| v.is_finite()));
    let (before, after) = (mse(&raw.image, &truth), mse(&oidn.image, &truth));
    eprintln!("MSE to the 256-spp image: raw {before}, oidn {after}");
    assert!(after < 0.5 * before, "raw {before}, oidn {after}");
    let again = r
        .render(&phantom(2, 1, Some(Denoise::Oidn)), &|_| {})
        .unwrap();
    assert_eq!(again.image, oidn.image);
}

#[test]
fn denoise_is_a_path_setting_only() {
    let mut s = phantom(1, 0, Some(Denoise::Atrous));
    s.lighting = s.lighting.for_model(LightingModel::Path);
    assert_eq!(s.lighting.denoise, Some(Denoise::Atrous));
    let local = s.lighting.for_model(LightingModel::Local);
    assert_eq!(local.denoise, None);
    let mut bad = s.clone();
    bad.lighting = Lighting {
        model: LightingModel::Shadows,
        denoise: Some(Denoise::Atrous),
        ..Lighting::default()
    };
    let err = Renderer::open(&bad, &ReadOptions::default())
        .unwrap()
        .render(&bad, &|_| {})
        .unwrap_err();
    assert!(err.to_string().contains("lighting.denoise"), "{err}");
}
