//! The GPU back end against the CPU on whatever adapter the machine has (Mesa's
//! lavapipe in CI: scripts/install-deps installs it). Without an adapter the tests
//! are skipped, and fail in strict mode (GLINT_STRICT or CI), naming what is missing.

use std::sync::Arc;

use glint_analysis::image::{delta_e_map, Srgb8Image};
use glint_core::camera::{CameraSpec, Projection};
use glint_core::{Clip, ClipPlane, CropBox, Image, Light, Material, RenderMode, Shader};
use glint_gpu::{Choice, Gpu, GpuError};
use glint_io::{Samples, Volume};
use glint_lobe::{CosTable, Geometry, LobeKind, Specular};
use glint_volume::phantom::Phantom;
use glint_volume::{
    presets, Classification, ClassifySettings, ColourVolume, Field, Filter, FrameSettings,
    Prefilter, Sampling, ShadowSettings, TransferFunction, Transport,
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
    let settings = ClassifySettings {
        mode,
        ..Default::default()
    };
    head_with(size, Filter::Trilinear, settings)
}

/// The iso value of the tests' iso frames: half the head phantom's largest value
/// (inside its bone layer's ramp).
const ISO_SHARE: f32 = 0.5;

/// [`head`] reconstructed with `filter` and classified with `settings` (an iso
/// frame's threshold set to [`ISO_SHARE`] of the range).
fn head_with(size: usize, filter: Filter, mut settings: ClassifySettings) -> Classification {
    let volume = Phantom::Head.volume(size).unwrap();
    let field = Field::with_prefilter(&volume, Prefilter::Binomial).unwrap();
    let field = Arc::new(field.with_filter(filter));
    let tf = presets::preset(Phantom::Head.preset())
        .unwrap()
        .transfer_function(field.range().1 as f64)
        .unwrap();
    settings.iso = ISO_SHARE * field.range().1;
    Classification::new(field, &tf, &settings).unwrap()
}

/// The CPU's and the GPU's frames of `class`: within [`MAX_DELTA_E`] and an opacity
/// within 0.02, and the volume covering more than `cover` of the GPU's frame.
/// Returns the largest opacity difference.
fn matches(
    gpu: &mut Gpu,
    class: &Classification,
    shader: &Shader,
    settings: &FrameSettings,
    (name, cover): (&str, f64),
) -> f32 {
    let cpu = class
        .frame(shader, settings, None, Transport::Local, &|_| {})
        .unwrap();
    let got = gpu.render_local(class, shader, settings).unwrap();
    let (de, covered) = max_delta_e(&cpu, &got);
    let da = cpu
        .alpha
        .iter()
        .zip(&got.alpha)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    eprintln!("{name}: max ΔE00 {de:.3}, max |Δalpha| {da:.4}, covered {covered:.2}");
    assert!(covered > cover, "{name}: only {covered} covered");
    assert!(de <= MAX_DELTA_E, "{name}: max ΔE00 {de}");
    assert!(da < 0.02, "{name}: alpha differs by {da}");
    da
}

/// A clip through the phantom's middle: an oblique plane and a crop box that cuts
/// off the front of the head along z, in world mm.
fn clip(class: &Classification) -> Clip {
    let field = class.field();
    let [nx, ny, nz] = field.dims();
    let c = field.index_to_world([nx as f64 / 2.0, ny as f64 / 2.0, nz as f64 / 2.0]);
    let a = field.index_to_world([(nx - 1) as f64, (ny - 1) as f64, (nz - 1) as f64]);
    let b = field.index_to_world([0.0; 3]);
    let lo = [0, 1, 2].map(|i| a[i].min(b[i]));
    let hi = [0, 1, 2].map(|i| a[i].max(b[i]));
    Clip {
        planes: vec![ClipPlane {
            point: c,
            normal: [0.6, -0.3, 0.5],
        }],
        crop: Some(CropBox {
            min: [lo[0] - 1.0, lo[1] - 1.0, lo[2] - 1.0],
            max: [hi[0] + 1.0, hi[1] + 1.0, 0.5 * (c[2] + hi[2])],
        }),
    }
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
    // A volume longer than the adapter's 3D texture side (small: 2 x 2 across): paged
    // into an atlas within the side, it renders as the CPU renders it.
    let long = gpu.adapter().max_texture_3d as usize + 1;
    let volume = Volume::new([long, 2, 2], [1.0; 3], Samples::F32(vec![1.0; long * 4])).unwrap();
    let field = Arc::new(Field::new(&volume).unwrap());
    let tf = TransferFunction::from_flat(&[0.0, 0.0, 1.0, 0.5], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let too_long = Classification::new(field, &tf, &ClassifySettings::default()).unwrap();
    let got = gpu.render_local(&too_long, &shader, &settings).unwrap();
    let cpu = too_long
        .frame(&shader, &settings, None, Transport::Local, &|_| {})
        .unwrap();
    assert!(max_delta_e(&cpu, &got).0 <= MAX_DELTA_E);
    // Past what an atlas within the side holds (48^3 voxels under a side of 32): a
    // typed error, one line, naming the volume and the side.
    let mut small = self::gpu().unwrap();
    small.limit_texture_side(32);
    match small.render_local(&class, &shader, &settings) {
        Err(e @ GpuError::Unsupported(_)) => {
            let line = e.to_string();
            assert!(
                line.contains("48x48x48") && line.contains("side of 32") && !line.contains('\n'),
                "{line}"
            );
        }
        other => panic!("expected Unsupported, got {:?}", other.map(|_| ())),
    }
}

/// A field past the texture side, paged into an atlas (pages of 16 voxels for a
/// 24x24x96 volume under a side of 48, the air pages sharing a slot): the same image,
/// bit for bit, as the plain textures give, for composite, tricubic iso and swept
/// `shadows` frames, and within the bound of the CPU's.
#[test]
fn gpu_paged_fields_render_as_the_plain_textures_do() {
    let Some(mut plain) = gpu() else { return };
    let mut paged = gpu().unwrap();
    paged.limit_texture_side(48);
    assert_eq!(paged.texture_side(), 48);
    let dims = [24usize, 24, 96];
    let mut v = Vec::with_capacity(24 * 24 * 96);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                // Three balls along z in air (0): the pages above and below are flat.
                let (x, y) = (i as f32 - 11.5, j as f32 - 11.5);
                let z = ((k as f32 - 8.0) % 32.0) - 12.0;
                let r = (x * x + y * y + z * z).sqrt();
                v.push(if !(8..88).contains(&k) {
                    0.0
                } else {
                    (10.0 - r).clamp(0.0, 4.0) * 250.0
                });
            }
        }
    }
    let volume = Volume::new(dims, [1.0, 1.0, 1.5], Samples::F32(v)).unwrap();
    let tf = TransferFunction::from_flat(&[0.0, 0.0, 1000.0, 0.6], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let lit = shader(LobeKind::EnergyFit, Geometry::Phong);
    let settings = frame(48, 64);
    let bits = |i: &Image| -> Vec<u32> {
        i.rgb
            .iter()
            .flatten()
            .chain(&i.alpha)
            .map(|x| x.to_bits())
            .collect()
    };
    for (name, filter, mode) in [
        ("composite", Filter::Trilinear, RenderMode::Composite),
        ("tricubic iso", Filter::Tricubic, RenderMode::Iso),
    ] {
        let field = Field::with_prefilter(&volume, Prefilter::Binomial).unwrap();
        let field = Arc::new(field.with_filter(filter));
        let classify = ClassifySettings {
            mode,
            iso: 500.0,
            ..Default::default()
        };
        let class = Classification::new(field, &tf, &classify).unwrap();
        let a = plain.render_local(&class, &lit, &settings).unwrap();
        let b = paged.render_local(&class, &lit, &settings).unwrap();
        assert!(bits(&a) == bits(&b), "{name}: paged differs from plain");
        let (de, covered) = max_delta_e(
            &class
                .frame(&lit, &settings, None, Transport::Local, &|_| {})
                .unwrap(),
            &b,
        );
        eprintln!("paged {name}: bit-identical to plain, max ΔE00 {de:.3} to the CPU, covered {covered:.2}");
        assert!(
            covered > 0.03 && de <= MAX_DELTA_E,
            "{name}: {de}, {covered}"
        );
        if mode == RenderMode::Composite {
            let on = ShadowSettings { occlusion: true };
            let a = plain
                .render_shadows_swept(&class, &lit, &settings, &on)
                .unwrap();
            let b = paged
                .render_shadows_swept(&class, &lit, &settings, &on)
                .unwrap();
            assert!(bits(&a) == bits(&b), "shadows: paged differs from plain");
        }
    }
}

#[test]
fn gpu_colour_volume_frames_match_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let shader = shader(LobeKind::EnergyFit, Geometry::Phong);
    let settings = frame(64, 64);
    let dims = [48; 3];
    // Red alternating from voxel to voxel, green and blue ramps: the interpolation
    // between the corners shows.
    let mut codes = Vec::with_capacity(48 * 48 * 48);
    for k in 0..48u32 {
        for j in 0..48u32 {
            for i in 0..48u32 {
                let red = (i + j + k) % 2 * 200 + 30;
                codes.push([red, 255 - j * 5, 60 + k * 4].map(|c| c as u8));
            }
        }
    }
    let colours = Arc::new(ColourVolume::new(dims, codes).unwrap());
    for mode in [RenderMode::Composite, RenderMode::Iso] {
        let settings_of = ClassifySettings {
            mode,
            ..Default::default()
        };
        let class = head_with(48, Filter::Trilinear, settings_of)
            .with_colour(colours.clone())
            .unwrap();
        let name = format!("{mode:?} colour volume");
        matches(&mut gpu, &class, &shader, &settings, (&name, 0.2));
        // The colours show: the frame differs from the table's colours.
        let plain = head_with(48, Filter::Trilinear, settings_of);
        let a = gpu.render_local(&class, &shader, &settings).unwrap();
        let b = gpu.render_local(&plain, &shader, &settings).unwrap();
        assert_ne!(a.rgb, b.rgb, "{name}: the colours changed nothing");
    }
}

#[test]
fn gpu_iso_and_tricubic_frames_match_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let shader = shader(LobeKind::EnergyFit, Geometry::Blinn);
    let settings = frame(64, 64);
    let iso = ClassifySettings {
        mode: RenderMode::Iso,
        ..Default::default()
    };
    let composite = ClassifySettings::default();
    for (name, filter, s) in [
        ("iso", Filter::Trilinear, iso),
        ("iso tricubic", Filter::Tricubic, iso),
        ("composite tricubic", Filter::Tricubic, composite),
    ] {
        let class = head_with(48, filter, s);
        matches(&mut gpu, &class, &shader, &settings, (name, 0.2));
    }
}

#[test]
fn gpu_clipped_frames_match_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let shader = shader(LobeKind::Exact, Geometry::Phong);
    for mode in [RenderMode::Composite, RenderMode::Iso, RenderMode::Mip] {
        let class = head(48, mode);
        let mut settings = frame(64, 64);
        settings.clip = clip(&class);
        let name = format!("{mode:?} clipped");
        matches(&mut gpu, &class, &shader, &settings, (&name, 0.1));
        // The clip shows: the unclipped frame differs.
        let whole = gpu.render_local(&class, &shader, &frame(64, 64)).unwrap();
        let cut = gpu.render_local(&class, &shader, &settings).unwrap();
        assert_ne!(whole.alpha, cut.alpha, "{name}: the clip cut nothing");
    }
}

#[test]
fn gpu_preintegrated_and_hw_table_frames_match_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let settings = frame(64, 64);
    let pre = head_with(
        48,
        Filter::Trilinear,
        ClassifySettings {
            sampling: Sampling::PreIntegrated,
            ..Default::default()
        },
    );
    let blinn = shader(LobeKind::Exact, Geometry::Blinn);
    matches(&mut gpu, &pre, &blinn, &settings, ("pre-integrated", 0.2));
    // The segments are not the point samples (the tables were read).
    let point = head(48, RenderMode::Composite);
    let a = gpu.render_local(&pre, &blinn, &settings).unwrap();
    let b = gpu.render_local(&point, &blinn, &settings).unwrap();
    assert_ne!(
        a.rgb, b.rgb,
        "pre-integrated frame equals the point-sampled one"
    );
    // A table as a hardware unit's: pow(c, 40) quantised to 8 bits, over codes of
    // 2^-6 (coarse, so that a code off by one shows).
    let table = CosTable::from_fn(6, |code| {
        let c = code as f32 / 64.0;
        (c.max(0.0).powf(40.0) * 255.0).round() / 255.0
    })
    .unwrap();
    let lights = vec![Light::HEADLIGHT];
    let hw = Shader::with_specular(
        Specular::from(table),
        Geometry::Phong,
        Material::default(),
        lights,
        0.0,
    )
    .unwrap();
    let class = head(48, RenderMode::Composite);
    matches(&mut gpu, &class, &hw, &settings, ("hw table", 0.2));
    // The table is not the closed form it quantises.
    let exact = Shader::new(
        LobeKind::Exact,
        40.0,
        4,
        Geometry::Phong,
        Material::default(),
        vec![Light::HEADLIGHT],
        0.0,
    )
    .unwrap();
    let a = gpu.render_local(&class, &hw, &settings).unwrap();
    let b = gpu.render_local(&class, &exact, &settings).unwrap();
    assert_ne!(a.rgb, b.rgb, "the hw table's frame equals pow's");
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

#[test]
fn gpu_preintegrated_faint_tissue_above_dense_bins_matches_the_cpu() {
    // The value is the distance (mm) from the centre: an opaque core at the lowest
    // values, then a faint shell. The shell's bins lie above the core's, where the
    // integrals are large: in plain f32 a segment's difference of two of them loses
    // most of the shell's extinction (the CPU keeps them in f64, the GPU in f32
    // pairs).
    let Some(mut gpu) = gpu() else { return };
    let n = 40;
    let c = (n - 1) as f32 / 2.0;
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d = [i, j, k].map(|x| (x as f32 - c).powi(2));
                v.push((d[0] + d[1] + d[2]).sqrt());
            }
        }
    }
    let volume = Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap();
    let field = Arc::new(Field::new(&volume).unwrap());
    let tf = TransferFunction::from_flat(
        &[0.0, 1.0, 8.0, 1.0, 8.2, 0.02, 17.0, 0.02, 17.2, 0.0],
        &[0.0, 0.9, 0.3, 0.2, 8.0, 0.9, 0.3, 0.2, 8.2, 0.3, 0.6, 1.0],
    )
    .unwrap();
    let settings = ClassifySettings {
        sampling: Sampling::PreIntegrated,
        ..Default::default()
    };
    let class = Classification::new(field, &tf, &settings).unwrap();
    let shader = shader(LobeKind::Exact, Geometry::Phong);
    let da = matches(
        &mut gpu,
        &class,
        &shader,
        &frame(48, 48),
        ("pre-integrated faint shell", 0.2),
    );
    // Opacity to 1e-3: the f32 pairs keep the integrals' difference to about 2^-24
    // of the segment's own (lavapipe: 0.0000); plain f32 integrals (the low halves
    // dropped) differ by 0.005 here.
    assert!(da <= 1e-3, "faint shell: alpha differs by {da}");
}

/// The `shadows` model: the light volumes built on the CPU and read by the GPU's
/// march, in composite (with and without ambient occlusion, a pure medium with an
/// anisotropic phase function) and iso
/// frames, against the CPU's frames through the same light volumes; MIP refused as
/// the CPU refuses it; light volumes of another camera refused.
#[test]
fn gpu_shadows_frames_match_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let settings = frame(64, 64);
    let lit = shader(LobeKind::EnergyFit, Geometry::Phong);
    let medium = lit
        .clone()
        .with_surface_weight(0.0)
        .unwrap()
        .with_anisotropy(0.4)
        .unwrap();
    let iso = ClassifySettings {
        mode: RenderMode::Iso,
        ..Default::default()
    };
    let cases = [
        ("shadows", ClassifySettings::default(), &lit, false),
        ("shadows occlusion", ClassifySettings::default(), &lit, true),
        ("shadows medium", ClassifySettings::default(), &medium, true),
        ("shadows iso", iso, &lit, true),
    ];
    for (name, classify, shader, occlusion) in cases {
        let class = head_with(48, Filter::Trilinear, classify);
        let lights = class
            .shadow_field(shader, &settings, &ShadowSettings { occlusion }, None)
            .unwrap();
        let cpu = class
            .frame(
                shader,
                &settings,
                None,
                Transport::Shadows(&lights),
                &|_| {},
            )
            .unwrap();
        let local = class
            .frame(shader, &settings, None, Transport::Local, &|_| {})
            .unwrap();
        let got = gpu
            .render_shadows(&class, shader, &settings, &lights)
            .unwrap();
        let (de, covered) = max_delta_e(&cpu, &got);
        // The shadows must show: the GPU's frame is not the local one.
        let (de_local, _) = max_delta_e(&local, &got);
        eprintln!("{name}: max ΔE00 {de:.3} (against local {de_local:.3}), covered {covered:.2}");
        assert!(covered > 0.2, "{name}: only {covered} covered");
        assert!(de <= MAX_DELTA_E, "{name}: max ΔE00 {de}");
        assert!(de_local > 5.0, "{name}: no shadow shows ({de_local})");
        // The light volumes swept on the GPU instead of the CPU's.
        let swept = ShadowSettings { occlusion };
        let got = gpu
            .render_shadows_swept(&class, shader, &settings, &swept)
            .unwrap();
        let (de, _) = max_delta_e(&cpu, &got);
        eprintln!("{name} swept on the GPU: max ΔE00 {de:.3}");
        assert!(de <= MAX_DELTA_E, "{name} swept: max ΔE00 {de}");
    }
    // Clipped: the light volumes are the CPU's (the clip empties grid points).
    let class = head(48, RenderMode::Composite);
    let mut clipped = frame(64, 64);
    clipped.clip = clip(&class);
    let on = ShadowSettings { occlusion: true };
    let lights = class.shadow_field(&lit, &clipped, &on, None).unwrap();
    let cpu = class
        .frame(&lit, &clipped, None, Transport::Shadows(&lights), &|_| {})
        .unwrap();
    let got = gpu
        .render_shadows_swept(&class, &lit, &clipped, &on)
        .unwrap();
    let (de, _) = max_delta_e(&cpu, &got);
    eprintln!("shadows clipped: max ΔE00 {de:.3}");
    assert!(de <= MAX_DELTA_E, "shadows clipped: max ΔE00 {de}");
    let class = head(48, RenderMode::Mip);
    let lights = class
        .shadow_field(&lit, &settings, &ShadowSettings::default(), None)
        .unwrap();
    let e = gpu
        .render_shadows(&class, &lit, &settings, &lights)
        .unwrap_err();
    assert!(e.to_string().contains("MIP is not lit"), "{e}");
    let class = head(48, RenderMode::Composite);
    let mut turned = frame(64, 64);
    turned.camera.azimuth += 90.0;
    let e = gpu
        .render_shadows(&class, &lit, &turned, &lights)
        .unwrap_err();
    assert!(e.to_string().contains("other lights"), "{e}");
}

/// The swept light volumes are kept across frames while what they were swept from
/// is the same, as the CPU keeps its own: a second frame, a zoom, an image size or
/// an exposure of the same lights sweep nothing, and match the CPU's frame; turning
/// the camera (the lights are camera-relative) or a new classification sweeps again.
#[test]
fn gpu_swept_light_volumes_are_kept_while_their_inputs_are_the_same() {
    let Some(mut gpu) = gpu() else { return };
    let lit = shader(LobeKind::EnergyFit, Geometry::Phong);
    let on = ShadowSettings { occlusion: true };
    let class = head(48, RenderMode::Composite);
    let render = |gpu: &mut Gpu, class: &Classification, settings: &FrameSettings| {
        let got = gpu
            .render_shadows_swept(class, &lit, settings, &on)
            .unwrap();
        let lights = class.shadow_field(&lit, settings, &on, None).unwrap();
        let cpu = class
            .frame(&lit, settings, None, Transport::Shadows(&lights), &|_| {})
            .unwrap();
        let (de, covered) = max_delta_e(&cpu, &got);
        assert!(covered > 0.2, "only {covered} covered");
        assert!(de <= MAX_DELTA_E, "max ΔE00 {de}");
        gpu.sweeps_run()
    };
    let settings = frame(64, 64);
    let first = render(&mut gpu, &class, &settings);
    assert_eq!(render(&mut gpu, &class, &settings), first, "the same frame");
    let mut zoomed = frame(48, 40);
    zoomed.camera.zoom = 1.6;
    assert_eq!(
        render(&mut gpu, &class, &zoomed),
        first,
        "a zoom and a size"
    );
    let mut turned = frame(64, 64);
    turned.camera.azimuth += 60.0;
    let after_turn = render(&mut gpu, &class, &turned);
    assert_eq!(after_turn, first + 1, "a turned camera turns the lights");
    let other = head(48, RenderMode::Composite);
    assert_eq!(
        render(&mut gpu, &other, &turned),
        after_turn + 1,
        "another classification"
    );
}
