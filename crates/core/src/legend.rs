//! A legend drawn into an image: a swatch and a name per entry, like the colour bar
//! of scalar overlays ([`ScalarColors::draw_bar`](crate::ScalarColors::draw_bar)),
//! for the labels of a label map.

use crate::colormap::draw_text;
use crate::Image;

/// Names and colours (linear RGB) to list in the image's top-left corner.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Legend {
    /// The entries, top to bottom.
    pub entries: Vec<(String, [f32; 3])>,
}

/// Text height: 1/this of the image's smaller side, at least [`MIN_PX`].
const HEIGHT_DIV: f32 = 48.0;
/// Smallest text height, pixels (DejaVu Sans stays legible at 8 px).
const MIN_PX: f32 = 8.0;
/// Largest share of the image height the rows may take (then "+N more").
const MAX_HEIGHT: f32 = 1.0 / 3.0;
/// Largest share of the image width a name may take (longer names end in "…").
const MAX_NAME_WIDTH: f32 = 0.22;

impl Legend {
    /// Draws the entries in the top-left corner: a square swatch of the colour then
    /// the name in white, one row each. The legend is scaled to the image: text
    /// 1/48 of its smaller side (at least 8 px), rows down to at most a third of its
    /// height (when they do not all fit, the last row says how many were left out),
    /// names cut to 22% of its width, so it covers at most a tenth of the image
    /// whatever the labels. Images smaller than 64 x 64 are left unchanged.
    pub fn draw(&self, image: &mut Image) {
        let (w, h) = (image.width as usize, image.height as usize);
        if h < 64 || w < 64 || self.entries.is_empty() {
            return;
        }
        let px = (w.min(h) as f32 / HEIGHT_DIV).max(MIN_PX);
        let row = (px * 1.35).ceil() as usize;
        let margin = (w.min(h) / 40).max(2);
        let rows = ((h as f32 * MAX_HEIGHT) as usize).saturating_sub(margin) / row;
        if rows == 0 {
            return;
        }
        let fits = self.entries.len() <= rows;
        let shown = if fits { self.entries.len() } else { rows - 1 };
        let side = px.round() as usize;
        let room = w as f32 * MAX_NAME_WIDTH;
        for (r, (name, color)) in self.entries.iter().take(shown).enumerate() {
            let y0 = margin + r * row;
            for y in y0..(y0 + side).min(h) {
                for x in margin..(margin + side).min(w) {
                    let k = y * w + x;
                    image.rgb[k] = *color;
                    image.alpha[k] = 1.0;
                }
            }
            let name = fitted(name, px, room);
            let x = (margin + side) as f32 + px / 2.0;
            draw_text(
                image,
                &name,
                x + text_width(&name, px),
                (y0 + side / 2) as f32,
                px,
            );
        }
        if !fits {
            let more = format!("+{} more", self.entries.len() - shown);
            let y = margin + shown * row + side / 2;
            draw_text(
                image,
                &more,
                margin as f32 + text_width(&more, px),
                y as f32,
                px,
            );
        }
    }
}

/// `name`, cut and ended with "…" when it is wider than `room` pixels at `px`.
fn fitted(name: &str, px: f32, room: f32) -> String {
    if text_width(name, px) <= room {
        return name.to_string();
    }
    let mut cut: String = name.to_string();
    while cut.pop().is_some() {
        let candidate = format!("{cut}…");
        if text_width(&candidate, px) <= room || cut.is_empty() {
            return candidate;
        }
    }
    "…".into()
}

/// The width of `text` at `px` pixels in the font [`draw_text`] uses.
fn text_width(text: &str, px: f32) -> f32 {
    use ab_glyph::{Font, FontRef, ScaleFont};
    let Ok(font) = FontRef::try_from_slice(dejavu::sans::regular()) else {
        return 0.0;
    };
    let scaled = font.as_scaled(px);
    text.chars()
        .map(|c| scaled.h_advance(font.glyph_id(c)))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn black(w: u32, h: u32) -> Image {
        let n = (w * h) as usize;
        Image {
            width: w,
            height: h,
            rgb: vec![[0.0; 3]; n],
            alpha: vec![0.0; n],
            stats: Default::default(),
        }
    }

    #[test]
    fn swatches_take_the_entry_colours_and_names_are_drawn_beside_them() {
        let mut image = black(256, 256);
        let legend = Legend {
            entries: vec![
                ("liver".into(), [0.5, 0.1, 0.0]),
                ("aorta".into(), [0.8, 0.0, 0.0]),
            ],
        };
        legend.draw(&mut image);
        // 256 px: text 8 px (256 / 48 is below the least).
        let (margin, px) = (256 / 40, 8.0f32);
        let row = (px * 1.35).ceil() as usize;
        // The centre of each swatch.
        let at = |r: usize| image.rgb[(margin + r * row + 5) * 256 + margin + 5];
        assert_eq!(at(0), [0.5, 0.1, 0.0]);
        assert_eq!(at(1), [0.8, 0.0, 0.0]);
        // Text: some white-ish pixels right of the first swatch, none far right.
        let lit = |x0: usize, x1: usize| {
            (margin..margin + row).any(|y| (x0..x1).any(|x| image.rgb[y * 256 + x][1] > 0.5))
        };
        assert!(lit(margin + 12, margin + 60));
        assert!(!lit(200, 256));
    }

    #[test]
    fn too_many_entries_end_with_a_count() {
        let mut few = black(128, 128);
        let entries: Vec<_> = (0..50)
            .map(|k| (format!("l{k}"), [1.0, 0.0, 0.0]))
            .collect();
        Legend { entries }.draw(&mut few);
        // 128 px: text 8 px, rows of 11 px in 128 / 3 - 3: 3 rows, 2 swatches of
        // 8 x 8 and "+48 more".
        let red = few.rgb.iter().filter(|c| **c == [1.0, 0.0, 0.0]).count();
        assert_eq!(red, 2 * 8 * 8);
    }

    /// Issue 42: 118 labels with long names (TotalSegmentator's) on a 384x384 image
    /// covered a third of it; now the lit pixels' bounding box is at most a tenth.
    #[test]
    fn the_legend_is_scaled_to_the_image() {
        for (w, h) in [(384, 384), (1024, 768), (256, 512)] {
            let mut image = black(w, h);
            let entries: Vec<_> = (0..118)
                .map(|k| (format!("iliopsoas_muscle_left_{k}"), [0.0, 1.0, 0.0]))
                .collect();
            Legend { entries }.draw(&mut image);
            let (mut x1, mut y1) = (0, 0);
            for (k, c) in image.rgb.iter().enumerate() {
                if c.iter().any(|&v| v > 0.0) {
                    x1 = x1.max(k % w as usize + 1);
                    y1 = y1.max(k / w as usize + 1);
                }
            }
            let share = (x1 * y1) as f64 / (w * h) as f64;
            eprintln!("legend share {w}x{h}: {share:.3}");
            assert!(share > 0.02 && share <= 0.1, "{w}x{h}: {share}");
            assert!(3 * y1 <= h as usize, "{w}x{h}: {y1}");
        }
    }
}
