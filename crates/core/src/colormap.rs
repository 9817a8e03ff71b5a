//! Colour maps for per-vertex scalars (curvature, sulcal depth, thickness) and the
//! colour bar drawn beside them. The maps are d3-scale-chromatic's, through the
//! `colorous` crate (viridis and its relatives are matplotlib's, by van der Walt and
//! Smith); glint only samples them into a linear-light table.

use crate::color::srgb_to_linear;
use crate::error::RenderError;
use crate::image::Image;

/// Entries of the linear-light table a [`ColorMap`] is sampled into: finer than the
/// 8-bit sRGB the maps are defined in, so the table adds no visible banding.
pub const COLORMAP_TABLE: usize = 1024;

/// A colour map for scalars.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = RenderError, parse_err_fn = crate::error::unknown_name::<Self>)]
pub enum ColorMap {
    /// Perceptually uniform, blue to yellow (matplotlib's default).
    #[default]
    Viridis,
    /// Perceptually uniform, black to yellow through red.
    Inferno,
    /// Perceptually uniform, black to light yellow through purple.
    Magma,
    /// Perceptually uniform, blue to yellow through magenta.
    Plasma,
    /// Perceptually uniform and readable with colour-vision deficiency.
    Cividis,
    /// Google's improved rainbow.
    Turbo,
    /// Black to white.
    Greys,
    /// Diverging red-white-blue, for signed scalars (low red, high blue).
    RdBu,
    /// Diverging, low light grey to high dark grey as FreeSurfer shows curvature and
    /// sulcal depth (binary-looking gyri and sulci).
    Sulc,
}

impl ColorMap {
    /// Every map, in the order `--help` lists them.
    pub const ALL: &'static [ColorMap] = <ColorMap as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`ColorMap::ALL`].
    pub const NAMES: &'static [&'static str] = <ColorMap as strum::VariantNames>::VARIANTS;

    /// The name users type.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The sRGB colour at `t` in `0..=1` (clamped), as 8-bit samples.
    fn srgb8(self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let g = match self {
            ColorMap::Viridis => colorous::VIRIDIS,
            ColorMap::Inferno => colorous::INFERNO,
            ColorMap::Magma => colorous::MAGMA,
            ColorMap::Plasma => colorous::PLASMA,
            ColorMap::Cividis => colorous::CIVIDIS,
            ColorMap::Turbo => colorous::TURBO,
            ColorMap::Greys => return colorous::GREYS.eval_continuous(1.0 - t).into_array(),
            ColorMap::RdBu => colorous::RED_BLUE,
            ColorMap::Sulc => {
                // Two greys with a short ramp at the middle (FreeSurfer's binary
                // curvature look): 0.35 sRGB below, 0.75 above.
                let s = ((t - 0.5) * 8.0 + 0.5).clamp(0.0, 1.0);
                let v = (255.0 * (0.75 - 0.4 * s)).round() as u8;
                return [v; 3];
            }
        };
        g.eval_continuous(t).into_array()
    }

    /// The linear-light colour at `t` in `0..=1` (clamped; NaN gives the low end).
    pub fn linear(self, t: f64) -> [f32; 3] {
        self.srgb8(t)
            .map(|c| srgb_to_linear(f64::from(c) / 255.0) as f32)
    }

    /// The map sampled into a [`COLORMAP_TABLE`]-entry linear table.
    pub fn table(self) -> Vec<[f32; 3]> {
        (0..COLORMAP_TABLE)
            .map(|i| self.linear(i as f64 / (COLORMAP_TABLE - 1) as f64))
            .collect()
    }
}

impl glint_lobe::names::Named for ColorMap {
    const WHAT: &'static str = "colour map";
}

/// Scenes name maps as users type them (`"viridis"`).
impl serde::Serialize for ColorMap {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for ColorMap {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

/// Scalars mapped through a colour map: values at or below `range.0` get the map's
/// low end, at or above `range.1` its high end.
#[derive(Clone, Debug)]
pub struct ScalarColors {
    /// The map.
    pub map: ColorMap,
    /// The values at the two ends of the map.
    pub range: (f32, f32),
    table: Vec<[f32; 3]>,
}

impl ScalarColors {
    /// A mapping of `range` through `map`; the range must be finite and increasing.
    pub fn new(map: ColorMap, range: (f32, f32)) -> Result<ScalarColors, RenderError> {
        if !range.0.is_finite() || !range.1.is_finite() || range.1 <= range.0 {
            return Err(RenderError::Parameter(format!(
                "scalar range {}..{}: expected finite numbers, low < high",
                range.0, range.1
            )));
        }
        Ok(ScalarColors {
            map,
            range,
            table: map.table(),
        })
    }

    /// The range a map should span for `values` (non-finite ones ignored): the 2nd to
    /// 98th percentile, so a few outliers do not wash the map out; symmetric about 0
    /// for the diverging maps when the values change sign. `None` when no value is
    /// finite or all are equal.
    pub fn robust_range(map: ColorMap, values: &[f32]) -> Option<(f32, f32)> {
        let mut v: Vec<f32> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        let pick = |v: &mut Vec<f32>, q: f64| {
            let k = ((v.len() - 1) as f64 * q).round() as usize;
            *v.select_nth_unstable_by(k, f32::total_cmp).1
        };
        let (mut lo, mut hi) = (
            pick(&mut v, ROBUST_QUANTILE),
            pick(&mut v, 1.0 - ROBUST_QUANTILE),
        );
        if matches!(map, ColorMap::RdBu | ColorMap::Sulc) && lo < 0.0 && hi > 0.0 {
            let m = lo.abs().max(hi);
            (lo, hi) = (-m, m);
        }
        (hi > lo).then_some((lo, hi))
    }

    /// The linear colour of scalar `s` (NaN gives the low end).
    #[inline]
    pub fn color(&self, s: f32) -> [f32; 3] {
        let t = (s - self.range.0) / (self.range.1 - self.range.0);
        let i = (t * (COLORMAP_TABLE - 1) as f32 + 0.5).clamp(0.0, (COLORMAP_TABLE - 1) as f32);
        // NaN clamps to NaN, which `as usize` turns into 0.
        self.table[i as usize]
    }

    /// Draws the colour bar: a vertical strip at the image's right edge, the map's
    /// high end at the top, with a one-pixel white frame and the range's ends written
    /// beside its ends. Images too small for a bar (under 64 pixels high or 32 wide)
    /// are left as they are.
    pub fn draw_bar(&self, image: &mut Image) {
        let (w, h) = (image.width as usize, image.height as usize);
        if h < 64 || w < 32 {
            return;
        }
        let bar_w = (w / BAR_WIDTH_DIV).max(4);
        let bar_h = h * 3 / 5;
        let x0 = w - bar_w - w / 40 - 1;
        let y0 = (h - bar_h) / 2;
        let frame = [1.0f32; 3];
        for y in y0 - 1..=y0 + bar_h {
            for x in x0 - 1..=x0 + bar_w {
                let inside = y >= y0 && y < y0 + bar_h && x >= x0 && x < x0 + bar_w;
                let c = if inside {
                    let t = 1.0 - (y - y0) as f64 / (bar_h - 1) as f64;
                    self.map.linear(t)
                } else {
                    frame
                };
                let k = y * w + x;
                image.rgb[k] = c;
                image.alpha[k] = 1.0;
            }
        }
        let px = (h as f32 / LABEL_HEIGHT_DIV).max(LABEL_MIN_PX);
        let right = x0 as f32 - 1.0 - px / 3.0;
        draw_text(image, &format_value(self.range.1), right, y0 as f32, px);
        draw_text(
            image,
            &format_value(self.range.0),
            right,
            (y0 + bar_h) as f32,
            px,
        );
    }
}

/// A colour-bar label: 3 significant digits, scientific notation for very large or
/// small magnitudes.
fn format_value(v: f32) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-2..1e4).contains(&a) {
        format!("{v:.2e}")
    } else {
        let digits = if a < 10.0 {
            2
        } else if a < 100.0 {
            1
        } else {
            0
        };
        format!("{v:.digits$}")
    }
}

/// Writes `text` in white, right-aligned at `right`, vertically centred on `y`, `px`
/// pixels high, blended over the image by glyph coverage. The glyphs are DejaVu Sans
/// (the `dejavu` crate, as glint-analysis's plots), rasterised by `ab_glyph`.
fn draw_text(image: &mut Image, text: &str, right: f32, y: f32, px: f32) {
    use ab_glyph::{point, Font, FontRef, ScaleFont};
    let Ok(font) = FontRef::try_from_slice(dejavu::sans::regular()) else {
        return;
    };
    let scaled = font.as_scaled(px);
    let width: f32 = text
        .chars()
        .map(|c| scaled.h_advance(font.glyph_id(c)))
        .sum();
    // Digits' height is about the ascent; centre them on `y`.
    let baseline = y + scaled.ascent() / 2.0 - 1.0;
    let mut x = right - width;
    let (w, h) = (image.width as i64, image.height as i64);
    for c in text.chars() {
        let id = font.glyph_id(c);
        let glyph = id.with_scale_and_position(px, point(x, baseline));
        x += scaled.h_advance(id);
        let Some(outline) = font.outline_glyph(glyph) else {
            continue;
        };
        let b = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let (px, py) = (
                b.min.x as i64 + i64::from(gx),
                b.min.y as i64 + i64::from(gy),
            );
            if (0..w).contains(&px) && (0..h).contains(&py) {
                let k = (py * w + px) as usize;
                let a = coverage.clamp(0.0, 1.0);
                image.rgb[k] = image.rgb[k].map(|c| c * (1.0 - a) + a);
                image.alpha[k] = image.alpha[k].max(a);
            }
        });
    }
}

/// Label height: 1/this of the image height, at least [`LABEL_MIN_PX`].
const LABEL_HEIGHT_DIV: f32 = 32.0;
/// Smallest label height, pixels (below this digits are unreadable).
const LABEL_MIN_PX: f32 = 10.0;

/// Quantile cut from each end by [`ScalarColors::robust_range`].
const ROBUST_QUANTILE: f64 = 0.02;

/// The colour bar is 1/this of the image width.
const BAR_WIDTH_DIV: usize = 40;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_match_matplotlib() {
        // matplotlib's _viridis_data: first entry (0.267004, 0.004874, 0.329415), last
        // (0.993248, 0.906157, 0.143936), sRGB.
        let lo = ColorMap::Viridis.srgb8(0.0).map(|c| c as f64 / 255.0);
        let hi = ColorMap::Viridis.srgb8(1.0).map(|c| c as f64 / 255.0);
        for (a, b) in lo.iter().zip([0.267004, 0.004874, 0.329415]) {
            assert!((a - b).abs() < 2.0 / 255.0, "{lo:?}");
        }
        for (a, b) in hi.iter().zip([0.993248, 0.906157, 0.143936]) {
            assert!((a - b).abs() < 2.0 / 255.0, "{hi:?}");
        }
    }

    #[test]
    fn scalars_clamp_to_the_ends_and_names_round_trip() {
        let s = ScalarColors::new(ColorMap::Greys, (-1.0, 1.0)).unwrap();
        assert_eq!(s.color(-5.0), s.color(-1.0));
        assert_eq!(s.color(f32::NAN), s.color(-1.0));
        // Greys runs black to white.
        assert!(s.color(-1.0)[0] < 0.01 && s.color(1.0)[0] > 0.99);
        for &m in ColorMap::ALL {
            assert_eq!(m.name().parse::<ColorMap>().unwrap(), m);
        }
        assert!("rainbow".parse::<ColorMap>().is_err());
        assert!(ScalarColors::new(ColorMap::Viridis, (1.0, 1.0)).is_err());
    }

    #[test]
    fn robust_range_ignores_outliers_and_centres_diverging_maps() {
        let mut v: Vec<f32> = (0..1000).map(|i| i as f32 / 999.0).collect();
        v.push(1e6);
        v.push(f32::NAN);
        let (lo, hi) = ScalarColors::robust_range(ColorMap::Viridis, &v).unwrap();
        assert!(lo < 0.03 && hi > 0.97 && hi < 1.0, "{lo} {hi}");
        let signed: Vec<f32> = (0..100).map(|i| i as f32 - 30.0).collect();
        let (lo, hi) = ScalarColors::robust_range(ColorMap::RdBu, &signed).unwrap();
        assert_eq!(lo, -hi);
        assert!(ScalarColors::robust_range(ColorMap::Viridis, &[2.0; 5]).is_none());
    }
}
