//! A scene's environment map (`lighting.environment_map`): an equirectangular
//! Radiance `.hdr` file (read by the `image` crate's HDR decoder), an OpenEXR file (the
//! `exr` crate, as `-o x.exr` writes), or a built-in map by name; turned about the
//! vertical axis and scaled by the scene's `environment_rotation` and
//! `environment_intensity`. Every error is one line ([`RenderError::EnvironmentMap`]):
//! a missing, truncated or malformed file, an absurd size (checked from the header,
//! before the texels are allocated), NaN or negative texels, an unknown name.
//!
//! The built-in `studio` is procedural (no download): three soft boxes (a warm key
//! above and in front of the patient's left, a cool fill in front of the right, a rim
//! light behind) over a dim floor-to-ceiling gradient, 512x256 texels.

use std::io::BufReader;
use std::path::Path;
use std::sync::Arc;

use glint_core::{check_env_size, EnvMap, RenderError};

use super::Lighting;

/// The built-in maps a scene names instead of a file.
pub const ENVIRONMENT_NAMES: [&str; 1] = ["studio"];

/// The environment map named by `map`: a built-in name ([`ENVIRONMENT_NAMES`]) or a
/// `.hdr` or `.exr` file.
pub fn load_environment(map: &str) -> Result<EnvMap, RenderError> {
    let err = |what: String| RenderError::EnvironmentMap {
        map: map.to_string(),
        what,
    };
    let fail = |e: RenderError| match e {
        RenderError::Parameter(what) => err(what),
        e => e,
    };
    if map == "studio" {
        return studio().map_err(fail);
    }
    let path = Path::new(map);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (w, h, texels) = match ext.as_deref() {
        Some("hdr") => read_hdr(path).map_err(err)?,
        Some("exr") => read_exr(path).map_err(err)?,
        _ => {
            return Err(err(format!(
                "expected a .hdr or .exr file or a built-in name ({})",
                ENVIRONMENT_NAMES.join(", ")
            )))
        }
    };
    EnvMap::new(w, h, texels).map_err(fail)
}

/// One line of an error's causes.
fn line(e: impl std::fmt::Display) -> String {
    e.to_string().replace('\n', " ")
}

/// A Radiance `.hdr` file's texels: the header's size checked before any is read.
fn read_hdr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), String> {
    use image::codecs::hdr::HdrDecoder;
    let file = std::fs::File::open(path).map_err(line)?;
    let decoder = HdrDecoder::new(BufReader::new(file)).map_err(line)?;
    let meta = decoder.metadata();
    check_env_size(meta.width, meta.height).map_err(line)?;
    let texels = decoder.read_image_hdr().map_err(line)?;
    Ok((
        meta.width,
        meta.height,
        texels.into_iter().map(|p| p.0).collect(),
    ))
}

/// An OpenEXR file's first RGB(A) layer: the header's size checked before any texel
/// is read.
fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), String> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(line)?;
    let header = meta.headers.first().ok_or("no layer")?;
    let size = header.layer_size;
    let (w, h) = (
        u32::try_from(size.width()).unwrap_or(u32::MAX),
        u32::try_from(size.height()).unwrap_or(u32::MAX),
    );
    check_env_size(w, h).map_err(line)?;
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px), p, (r, g, b, _): (f32, f32, f32, f32)| px[p.y() * *w + p.x()] = [r, g, b],
    )
    .map_err(line)?;
    let (read_w, texels) = image.layer_data.channel_data.pixels;
    if read_w != w as usize || texels.len() != w as usize * h as usize {
        return Err("the layer's size differs from its header's".into());
    }
    Ok((w, h, texels))
}

/// The built-in `studio` map (see the module docs).
fn studio() -> Result<EnvMap, RenderError> {
    let (w, h) = (512u32, 256u32);
    // Soft boxes: centre azimuth and elevation (degrees; azimuth from +x, the
    // patient's right in RAS+, towards +y, anterior), half sizes (degrees), radiance.
    let boxes: [([f32; 2], [f32; 2], [f32; 3]); 3] = [
        ([120.0, 35.0], [16.0, 11.0], [14.0, 13.0, 12.0]),
        ([45.0, 10.0], [13.0, 13.0], [2.6, 2.8, 3.0]),
        ([250.0, 45.0], [7.0, 16.0], [9.0, 9.0, 9.0]),
    ];
    let mut texels = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        let elev = 90.0 - 180.0 * (y as f32 + 0.5) / h as f32;
        // Dim floor, brighter ceiling, a soft horizon between.
        let s = (elev / 90.0).clamp(-1.0, 1.0);
        let base = 0.06 + 0.05 * s + 0.03 * (1.0 - s.abs());
        for x in 0..w {
            let az = 360.0 * (x as f32 + 0.5) / w as f32;
            let mut t = [base * 0.95, base, base * 1.08];
            for (c, half, l) in &boxes {
                let mut da = (az - c[0]).rem_euclid(360.0);
                if da > 180.0 {
                    da -= 360.0;
                }
                // Azimuthal extent measured on the sphere (shrinks towards the poles).
                let da = da * (elev.to_radians()).cos().max(0.0);
                let de = elev - c[1];
                // A soft edge: full inside, falling off over a quarter of the half size.
                let edge = |d: f32, half: f32| {
                    let k = (d.abs() - half) / (0.25 * half);
                    (1.0 - k).clamp(0.0, 1.0).min(1.0)
                };
                let wgt = edge(da, half[0]) * edge(de, half[1]);
                if wgt > 0.0 {
                    for i in 0..3 {
                        t[i] += wgt * l[i];
                    }
                }
            }
            texels.push(t);
        }
    }
    EnvMap::new(w, h, texels)
}

/// The last map a renderer loaded, for the lighting it was loaded for (a viewer
/// renders many frames of one map: its file is read and its distribution built once).
#[derive(Clone, Default)]
pub(crate) struct EnvCache {
    last: Option<(String, f64, f32, Arc<EnvMap>)>,
}

impl EnvCache {
    /// The map of a resolved `lighting`, when it names one.
    pub(crate) fn get(&mut self, lighting: &Lighting) -> Result<Option<Arc<EnvMap>>, RenderError> {
        let Some(name) = &lighting.environment_map else {
            return Ok(None);
        };
        let rotation = lighting.environment_rotation.unwrap_or(0.0);
        let intensity = lighting.environment_intensity.unwrap_or(1.0);
        if let Some((n, r, i, map)) = &self.last {
            if n == name && *r == rotation && *i == intensity {
                return Ok(Some(map.clone()));
            }
        }
        let map = Arc::new(load_environment(name)?.placed(rotation, intensity)?);
        self.last = Some((name.clone(), rotation, intensity, map.clone()));
        Ok(Some(map))
    }
}
