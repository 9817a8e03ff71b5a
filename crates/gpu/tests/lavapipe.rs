//! The GPU back end against the CPU on whatever adapter the machine has (Mesa's
//! lavapipe in CI: scripts/install-deps installs it). Without an adapter the tests
//! are skipped, and fail in strict mode (GLINT_STRICT or CI), naming what is missing.

use std::sync::Arc;

use glint_analysis::image::{delta_e_map, Srgb8Image};
use glint_core::camera::{CameraSpec, Projection};
use glint_core::{Image, Light, Material, RenderMode, Shader};
use glint_gpu::{Choice, Gpu, GpuError};
use glint_lobe::{Geometry, LobeKind};
use glint_volume::phantom::Phantom;
use glint_volume::{
    presets, Classification, ClassifySettings, Field, FrameSettings, Prefilter, Sampling, Transport,
};

/// The largest CIEDE2000 difference allowed between the GPU's and the CPU's pixel
/// (8-bit sRGB): the bound for `local` with f32 interpolation in the shader.
const MAX_DELTA_E: f64 = 1.0;

/// The device, or `None` after reporting it missing (a failure in strict mode).
fn gpu() -> Option<Gpu> {
    match Gpu::open(Choice::Any) {
        Ok(gpu) => {
            glint_testkit::ran(&format!("GPU adapter {}", gpu.adapter().name));
            Some(gpu)
        }
        Err(e) => {
            glint_testkit::missing(&format!(
                "a GPU adapter (Mesa's lavapipe: mesa-vulkan-drivers, scripts/install-deps): {e}"
            ));
            None
        }
    }
}

/// The head phantom on a `size`^3 grid with the scene's default prefilter, classified
/// by its preset in `mode`.
fn head(size: usize, mode: RenderMode) -> Classification {
    let volume = Phantom::Head.volume(size).unwrap();
    let field = Arc::new(Field::with_prefilter(&volume, Prefilter::Binomial).unwrap());
    let tf = presets::preset(Phantom::Head.preset())
        .unwrap()
        .transfer_function(field.range().1 as f64)
        .unwrap();
    let settings = ClassifySettings {
        mode,
        ..Default::default()
    };
    Classification::new(field, &tf, &settings).unwrap()
}

fn shader(kind: LobeKind, geometry: Geometry) -> Shader {
    let lights = vec![
        Light::HEADLIGHT,
        Light {
            azimuth: 40.0,
            elevation: 25.0,
            intensity: 0.7,
        },
    ];
    Shader::new(kind, 40.0, 4, geometry, Material::default(), lights, 0.0).unwrap()
}

fn frame(width: u32, height: u32) -> FrameSettings {
    FrameSettings {
        width,
        height,
        camera: CameraSpec {
            azimuth: 30.0,
            elevation: 20.0,
            ..Default::default()
        },
        background: [0.05, 0.1, 0.2],
        ..Default::default()
    }
}

/// The largest ΔE00 between two frames' 8-bit sRGB pixels, and the share of pixels
/// the GPU's frame shows anything of the volume in (so a blank pair cannot pass).
fn max_delta_e(cpu: &Image, gpu: &Image) -> (f64, f64) {
    let srgb = |i: &Image| Srgb8Image::from_linear(i.width, i.height, &i.rgb).unwrap();
    let de = delta_e_map(&srgb(cpu), &srgb(gpu)).unwrap();
    let covered = gpu.alpha.iter().filter(|&&a| a > 0.01).count() as f64 / gpu.alpha.len() as f64;
    (de.iter().cloned().fold(0.0, f64::max), covered)
}

#[test]
fn gpu_local_frames_match_the_cpu_for_every_lobe_and_geometry() {
    let Some(mut gpu) = gpu() else { return };
    let class = head(64, RenderMode::Composite);
    let settings = frame(64, 64);
    for &kind in LobeKind::ALL {
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let shader = shader(kind, geometry);
            let cpu = class
                .frame(&shader, &settings, None, Transport::Local, &|_| {})
                .unwrap();
            let got = gpu.render_local(&class, &shader, &settings).unwrap();
            let (de, covered) = max_delta_e(&cpu, &got);
            eprintln!("{kind} {geometry}: max ΔE00 {de:.3}");
            assert!(covered > 0.2, "{kind} {geometry}: only {covered} covered");
            assert!(de <= MAX_DELTA_E, "{kind} {geometry}: max ΔE00 {de}");
            // Opacity too, not only colour.
            let da = cpu
                .alpha
                .iter()
                .zip(&got.alpha)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(da < 0.02, "{kind} {geometry}: alpha differs by {da}");
        }
    }
}

#[test]
fn gpu_mip_and_orthographic_non_square_frames_match_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let shader = shader(LobeKind::EnergyFit, Geometry::Phong);
    let mip = head(48, RenderMode::Mip);
    let settings = frame(128, 96);
    let cpu = mip
        .frame(&shader, &settings, None, Transport::Local, &|_| {})
        .unwrap();
    let got = gpu.render_local(&mip, &shader, &settings).unwrap();
    let (de, covered) = max_delta_e(&cpu, &got);
    eprintln!("MIP: max ΔE00 {de:.3}");
    assert!(
        covered > 0.1 && de <= MAX_DELTA_E,
        "MIP: ΔE00 {de}, {covered}"
    );
    let composite = head(48, RenderMode::Composite);
    let mut ortho = frame(96, 128);
    ortho.camera.projection = Projection::Orthographic;
    let cpu = composite
        .frame(&shader, &ortho, None, Transport::Local, &|_| {})
        .unwrap();
    let got = gpu.render_local(&composite, &shader, &ortho).unwrap();
    let (de, covered) = max_delta_e(&cpu, &got);
    eprintln!("orthographic: max ΔE00 {de:.3}");
    assert!(
        covered > 0.2 && de <= MAX_DELTA_E,
        "orthographic: ΔE00 {de}, {covered}"
    );
}

#[test]
fn gpu_frames_repeat_bit_for_bit_and_refuse_what_they_cannot_render() {
    let Some(mut gpu) = gpu() else { return };
    let class = head(48, RenderMode::Composite);
    let shader = shader(LobeKind::Exact, Geometry::Blinn);
    let settings = frame(64, 64);
    let a = gpu.render_local(&class, &shader, &settings).unwrap();
    let b = gpu.render_local(&class, &shader, &settings).unwrap();
    let bits = |i: &Image| -> Vec<u32> {
        i.rgb
            .iter()
            .flatten()
            .chain(&i.alpha)
            .map(|x| x.to_bits())
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    // Pre-integrated sampling is not on the GPU yet: a typed error naming it.
    let field = class.field().clone();
    let tf = presets::preset("head")
        .unwrap()
        .transfer_function(field.range().1 as f64)
        .unwrap();
    let pre = ClassifySettings {
        sampling: Sampling::PreIntegrated,
        ..Default::default()
    };
    let pre = Classification::new(field, &tf, &pre).unwrap();
    match gpu.render_local(&pre, &shader, &settings) {
        Err(e @ GpuError::Unsupported(_)) => {
            let line = e.to_string();
            assert!(
                line.contains("pre-integrated") && !line.contains('\n'),
                "{line}"
            );
        }
        other => panic!("expected Unsupported, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn gpu_errors_are_one_line_each() {
    let errors = [
        GpuError::NoAdapter,
        GpuError::NoHardware {
            found: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
        },
        GpuError::NoCompute {
            adapter: "old".into(),
        },
        GpuError::Limits {
            adapter: "small".into(),
            what: "the largest 3D texture side",
            have: 256,
            need: 512,
        },
    ];
    for e in errors {
        let line = e.to_string();
        assert!(!line.is_empty() && !line.contains('\n'), "{line}");
    }
    assert!(GpuError::NoAdapter
        .to_string()
        .contains("mesa-vulkan-drivers"));
}
