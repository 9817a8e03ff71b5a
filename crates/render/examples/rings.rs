//! Renders a scene and prints the ring measure ([`glint_render::Image::ring_measure`])
//! and the time per frame: the tool behind docs/performance.md's ring figures.
//!
//! Usage: `cargo run --release -p glint-render --example rings -- [VOLUME|PHANTOM]
//! [PRESET] [STEP] [VIEW] [REPEAT] [OUT.png]` (defaults: the `head` phantom, its
//! preset, 0.5, anterior, 5, no PNG).

use std::time::Instant;

use glint_lobe::{Geometry, LobeKind};
use glint_render::{
    phantom::Phantom, preset, CameraSpec, Classification, Depth, Field, Light, RenderSettings,
    Shader, View,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let source = arg(0, "head");
    let t0 = Instant::now();
    let (volume, default_preset) = match source.parse::<Phantom>() {
        Ok(p) => (
            p.volume(
                std::env::var("RINGS_SIZE")
                    .ok()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(Phantom::DEFAULT_SIZE),
            )?,
            p.preset(),
        ),
        Err(_) => (
            glint_io::read_volume(source.as_ref(), &glint_io::ReadOptions::default())?,
            "mr-t2-brain",
        ),
    };
    let read = t0.elapsed();
    let t1 = Instant::now();
    let field = Field::new(&volume)?;
    let prep = t1.elapsed();
    let p = preset(&arg(1, default_preset))?;
    let tf = p.transfer_function(field.robust_range().1 as f64)?;
    let settings = RenderSettings {
        step: arg(2, "0.5").parse()?,
        camera: CameraSpec {
            view: arg(3, "anterior").parse::<View>()?,
            projection: if std::env::var_os("RINGS_ORTHO").is_some() {
                glint_render::Projection::Orthographic
            } else {
                glint_render::Projection::Perspective
            },
            ..Default::default()
        },
        skip_empty: std::env::var_os("RINGS_NOSKIP").is_none(),
        ..Default::default()
    };
    let repeat: u32 = arg(4, "5").parse()?;
    let t2 = Instant::now();
    let class = Classification::new(&field, &tf, &settings)?;
    let classify = t2.elapsed();
    let camera = class.camera(&settings)?;
    let mut lights = vec![(Light::HEADLIGHT.direction(&camera), 1.0)];
    if let Ok(l) = std::env::var("RINGS_LIGHT") {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        let light = Light {
            azimuth: v[0],
            elevation: v[1],
            intensity: v.get(2).copied().unwrap_or(1.0) as f32,
        };
        lights.push((light.direction(&camera), light.intensity));
    }
    let mut material = p.material();
    if std::env::var_os("RINGS_NOSHADE").is_some() {
        material.shade = false;
    }
    let shader = Shader::new(
        LobeKind::EnergyFit,
        p.material().power as f64,
        4,
        Geometry::Phong,
        material,
        lights,
        0.01 * (field.range().1 - field.range().0) / field.min_spacing() as f32,
    )?;
    let mut image = class.render(&shader, &settings, &|_| {})?;
    let t3 = Instant::now();
    for _ in 0..repeat {
        image = class.render(&shader, &settings, &|_| {})?;
    }
    let frame = t3.elapsed() / repeat.max(1);
    println!(
        "{source} preset {} step {}: ring measure {:.3}, frame {:.1} ms (read {:.1} ms, field {:.1} ms, classify {:.1} ms)",
        p.name,
        settings.step,
        image.ring_measure().unwrap_or(f64::NAN),
        frame.as_secs_f64() * 1e3,
        read.as_secs_f64() * 1e3,
        prep.as_secs_f64() * 1e3,
        classify.as_secs_f64() * 1e3,
    );
    if let Some(out) = args.get(5) {
        let mut t = glint_render::Timings::default();
        let bytes = t.time("encode", || image.encode_png(Depth::Eight))?;
        t.time("write", || {
            glint_render::Image::write_png_bytes(out.as_ref(), &bytes)
        })?;
        t.extend(field.timings());
        eprintln!("{t}");
    }
    Ok(())
}
