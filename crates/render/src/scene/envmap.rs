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
//! light behind) over a dim floor-to-ceiling gradient, 512x256 texels. The other names
//! ([`FETCHED_ENVIRONMENTS`]) are Poly Haven's CC0 probes as the npm package
//! `@pmndrs/assets` 1.7.0 ships them (512x256 OpenEXR, DWAB-compressed), which
//! `scripts/fetch-samples` writes to `$GLINT_DATA/samples/hdri/NAME.exr`.

use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glint_core::{check_env_size, EnvMap, RenderError};

use super::Lighting;

/// The built-in maps a scene names instead of a file.
pub const ENVIRONMENT_NAMES: [&str; 1] = ["studio"];

/// The maps a scene names that `scripts/fetch-samples` fetches (Poly Haven's CC0
/// probes from the npm package `@pmndrs/assets` 1.7.0; its own `studio` is left out,
/// the name being the built-in map's), read from [`fetched_environment`]'s path.
pub const FETCHED_ENVIRONMENTS: [&str; 17] = [
    "apartment",
    "bridge",
    "city",
    "dawn",
    "esplanade",
    "forest",
    "hall",
    "lab",
    "lobby",
    "night",
    "park",
    "sky",
    "sunrise",
    "sunset",
    "venice",
    "warehouse",
    "workshop",
];

/// The map names a scene can use here: the built-in ones and the fetched probes whose
/// file is present (a front end's choice of maps).
pub fn available_environments() -> Vec<&'static str> {
    (ENVIRONMENT_NAMES.iter().copied())
        .chain(
            (FETCHED_ENVIRONMENTS.iter().copied())
                .filter(|name| fetched_environment(name).is_file()),
        )
        .collect()
}

/// Where `scripts/fetch-samples` puts the fetched map `name`:
/// `$GLINT_DATA/samples/hdri/NAME.exr`, `GLINT_DATA` by default `~/.cache/glint`.
pub fn fetched_environment(name: &str) -> PathBuf {
    std::env::var_os("GLINT_DATA")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(std::env::var_os("HOME").unwrap_or_default()).join(".cache/glint")
        })
        .join("samples/hdri")
        .join(format!("{name}.exr"))
}

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
    let fetched = fetched_environment(map);
    let is_fetched = FETCHED_ENVIRONMENTS.contains(&map);
    let path = if is_fetched {
        if !fetched.is_file() {
            return Err(err(format!(
                "a probe that scripts/fetch-samples fetches, not at {} (run it, or set GLINT_DATA)",
                fetched.display()
            )));
        }
        fetched.as_path()
    } else {
        Path::new(map)
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (w, h, mut texels) = match ext.as_deref() {
        Some("hdr") => read_hdr(path).map_err(err)?,
        Some("exr") => read_exr(path).map_err(err)?,
        _ => {
            return Err(err(format!(
                "expected a .hdr or .exr file or a name ({}, or one that scripts/fetch-samples fetches: {})",
                ENVIRONMENT_NAMES.join(", "),
                FETCHED_ENVIRONMENTS.join(", ")
            )))
        }
    };
    if is_fetched {
        dering(w as usize, &mut texels);
    }
    EnvMap::new(w, h, texels).map_err(fail)
}

/// The side of OpenEXR's DWA blocks (an 8x8 DCT, aligned at the data window's origin).
const DWA_BLOCK: usize = 8;

/// Removes the negative texels that lossy DWAB compression leaves in the fetched probes
/// (its DCT rings beside bright sources: 11 to 3,684 texels per probe, down to -3,394
/// beside `sky`'s sun of 22,672), keeping each 8x8 block's sum per channel: the
/// negatives become 0 and the block's positive texels are scaled down by what that
/// added (a block whose sum is not positive becomes 0). Clamping alone would brighten
/// the sun probes by up to 12%. A user's file with a negative texel is still refused.
fn dering(width: usize, texels: &mut [[f32; 3]]) {
    if width == 0 {
        return;
    }
    let height = texels.len() / width;
    for by in (0..height).step_by(DWA_BLOCK) {
        for bx in (0..width).step_by(DWA_BLOCK) {
            let rows = by..(by + DWA_BLOCK).min(height);
            let cols = bx..(bx + DWA_BLOCK).min(width);
            for c in 0..3 {
                let (mut sum, mut positive) = (0f64, 0f64);
                for y in rows.clone() {
                    for t in &texels[y * width + cols.start..y * width + cols.end] {
                        sum += f64::from(t[c]);
                        positive += f64::from(t[c].max(0.0));
                    }
                }
                if sum == positive {
                    continue;
                }
                let scale = if sum > 0.0 {
                    (sum / positive) as f32
                } else {
                    0.0
                };
                for y in rows.clone() {
                    for t in &mut texels[y * width + cols.start..y * width + cols.end] {
                        t[c] = t[c].max(0.0) * scale;
                    }
                }
            }
        }
    }
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

#[cfg(test)]
mod tests {
    use super::dering;

    #[test]
    fn deringing_keeps_each_blocks_sum_and_leaves_no_negative() {
        // 16x8: two blocks. The left one rings (a bright texel beside negatives), the
        // right one is all negative in red.
        let mut t = vec![[1.0f32, 2.0, 0.5]; 16 * 8];
        t[3] = [50.0, 2.0, 0.5];
        t[4] = [-4.0, 2.0, 0.5];
        t[12] = [-1.0, 2.0, 0.5];
        for y in 0..8 {
            for x in 8..16 {
                t[y * 16 + x][0] = -0.25;
            }
        }
        let block_sum = |t: &[[f32; 3]], x0: usize, c: usize| -> f64 {
            (0..8)
                .flat_map(|y| (x0..x0 + 8).map(move |x| y * 16 + x))
                .map(|i| f64::from(t[i][c]))
                .sum()
        };
        let before = [
            block_sum(&t, 0, 0),
            block_sum(&t, 0, 1),
            block_sum(&t, 8, 1),
        ];
        dering(16, &mut t);
        assert!(t.iter().flatten().all(|v| *v >= 0.0));
        let after = [
            block_sum(&t, 0, 0),
            block_sum(&t, 0, 1),
            block_sum(&t, 8, 1),
        ];
        for (b, a) in before.iter().zip(after) {
            assert!((b - a).abs() < 1e-4 * b.abs(), "{b} -> {a}");
        }
        assert_eq!(t[4][0], 0.0);
        assert_eq!(block_sum(&t, 8, 0), 0.0);
        // Untouched channels stay bit for bit.
        assert_eq!(t[4][1], 2.0);
    }
}
