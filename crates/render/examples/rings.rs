//! Renders a scene and prints the ring measure ([`glint_render::Image::ring_measure`])
//! and the time per frame: the tool behind docs/performance.md's ring figures.
//!
//! Usage: `cargo run --release -p glint-render --example rings -- [VOLUME|PHANTOM]
//! [PRESET] [STEP] [VIEW] [REPEAT] [OUT.png]` (defaults: the `head` phantom, its
//! preset, 0.5, anterior, 5, no PNG). Environment: `RINGS_SIZE` (phantom grid),
//! `RINGS_ORTHO`, `RINGS_NOSKIP`, `RINGS_NOSHADE`, `RINGS_LIGHT=AZ,EL[,I]` (an extra
//! light), `RINGS_PREFILTER=binomial|none`, `RINGS_SAMPLING=point|pre-integrated`,
//! `RINGS_OPACITY_UNIT=MM` (the scene's `opacity_unit`), `RINGS_DEPTHS` (the measure at depths of
//! 6, 15, 30 and 60 px inside the silhouette), `RINGS_RAMP_GRID=G` (the phantom's
//! edges ramped as they are on a G^3 grid, whatever `RINGS_SIZE` is: the same object on
//! any grid).

use std::time::Instant;

use glint_render::{
    phantom::Phantom, Depth, Input, Light, Projection, ReadOptions, Renderer, Scene,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let env = |k: &str| std::env::var_os(k).is_some();
    let source = arg(0, "head");
    let input = match source.parse::<Phantom>() {
        Ok(name) => Input::Phantom {
            name,
            size: std::env::var("RINGS_SIZE")
                .ok()
                .and_then(|s| s.parse().ok())
                .unwrap_or(Phantom::DEFAULT_SIZE),
        },
        Err(_) => Input::Path(source.clone().into()),
    };
    let mut scene = Scene {
        input,
        preset: args.get(1).cloned(),
        step: arg(2, "0.5").parse()?,
        skip_empty: !env("RINGS_NOSKIP"),
        ..Scene::default()
    };
    scene.camera.view = arg(3, "anterior").parse()?;
    if env("RINGS_ORTHO") {
        scene.camera.projection = Projection::Orthographic;
    }
    if let Ok(p) = std::env::var("RINGS_PREFILTER") {
        scene.prefilter = p.parse()?;
    }
    if let Ok(p) = std::env::var("RINGS_SAMPLING") {
        scene.sampling = p.parse()?;
    }
    if let Ok(u) = std::env::var("RINGS_OPACITY_UNIT") {
        scene.opacity_unit = Some(u.parse()?);
    }
    if env("RINGS_NOSHADE") {
        scene.material.shade = Some(false);
    }
    if let Ok(l) = std::env::var("RINGS_LIGHT") {
        let v: Vec<f64> = l.split(',').map(|x| x.parse()).collect::<Result<_, _>>()?;
        scene.lights.push(Light {
            azimuth: v[0],
            elevation: v[1],
            intensity: v.get(2).copied().unwrap_or(1.0) as f32,
        });
    }
    let repeat: u32 = arg(4, "5").parse()?;
    let ramp_grid: Option<f64> = std::env::var("RINGS_RAMP_GRID")
        .ok()
        .map(|g| g.parse())
        .transpose()?;
    let mut renderer = match (&scene.input, ramp_grid) {
        (Input::Phantom { name, size }, Some(g)) => {
            use glint_render::phantom;
            let volume = match name {
                Phantom::SheppLogan => phantom::shepp_logan_with_ramp(*size, 2.0 * 2.0 / g)?,
                Phantom::Head => phantom::head_with_ramp(
                    *size,
                    phantom::HEAD_RAMP_VOXELS * 2.0 * phantom::MM_PER_UNIT / g,
                )?,
            };
            Renderer::from_source(volume, None)?
        }
        _ => Renderer::open(&scene, &ReadOptions::default())?,
    };
    let first = renderer.render(&scene, &|_| {})?;
    let resolved = renderer.resolve(&scene)?;
    let start = Instant::now();
    let mut image = first.image.clone();
    for _ in 0..repeat {
        image = renderer.render_resolved(resolved.clone(), &|_| {})?.image;
    }
    let frame = start.elapsed() / repeat.max(1);
    println!(
        "{source} preset {} step {}: ring measure {:.3}, frame {:.1} ms",
        first.scene.preset.as_deref().unwrap_or("(inline)"),
        scene.step,
        image.ring_measure().unwrap_or(f64::NAN),
        frame.as_secs_f64() * 1e3,
    );
    if env("RINGS_DEPTHS") {
        // The measure over the pixels at least d px inside the silhouette, and what
        // each band between two depths adds to the whole measure (at 6 px).
        let depths = [6usize, 15, 30, 60];
        let at: Vec<(f64, usize)> = depths
            .iter()
            .map(|&d| image.ring_measure_inside(d).unwrap_or((0.0, 0)))
            .collect();
        let total = at[0].1.max(1) as f64;
        for (i, &d) in depths.iter().enumerate() {
            let (m, n) = at[i];
            let (m_in, n_in) = at.get(i + 1).copied().unwrap_or((0.0, 0));
            let band = m * n as f64 - m_in * n_in as f64;
            println!(
                "  from {d} px inside: measure {m:.3} over {n} px; the band to the next depth adds {:.3}",
                band / total
            );
        }
    }
    let mut t = first.timings.clone();
    if let Some(out) = args.get(5) {
        let bytes = t.time("encode", || image.encode_png(Depth::Eight))?;
        t.time("write", || {
            glint_render::Image::write_png_bytes(out.as_ref(), &bytes)
        })?;
    }
    eprintln!("{t}");
    Ok(())
}
