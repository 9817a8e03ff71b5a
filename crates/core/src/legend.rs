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

/// Text height: 1/this of the image height, at least [`MIN_PX`] (the colour bar's
/// label size).
const HEIGHT_DIV: f32 = 40.0;
/// Smallest text height, pixels.
const MIN_PX: f32 = 10.0;

impl Legend {
    /// Draws the entries in the top-left corner: a square swatch of the colour then
    /// the name in white, one row each; when they do not all fit, the last row says
    /// how many were left out. Images smaller than 64 x 64 are left unchanged.
    pub fn draw(&self, image: &mut Image) {
        let (w, h) = (image.width as usize, image.height as usize);
        if h < 64 || w < 64 || self.entries.is_empty() {
            return;
        }
        let px = (h as f32 / HEIGHT_DIV).max(MIN_PX);
        let row = (px * 1.35).ceil() as usize;
        let margin = (w / 40).max(2);
        let rows = (h - 2 * margin) / row;
        if rows == 0 {
            return;
        }
        let fits = self.entries.len() <= rows;
        let shown = if fits { self.entries.len() } else { rows - 1 };
        let side = px.round() as usize;
        for (r, (name, color)) in self.entries.iter().take(shown).enumerate() {
            let y0 = margin + r * row;
            for y in y0..(y0 + side).min(h) {
                for x in margin..(margin + side).min(w) {
                    let k = y * w + x;
                    image.rgb[k] = *color;
                    image.alpha[k] = 1.0;
                }
            }
            let x = (margin + side) as f32 + px / 2.0;
            draw_text(
                image,
                name,
                x + text_width(name, px),
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
        let (margin, px) = (256 / 40, 10.0f32);
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
        // 128 px: rows of 14 px in 128 - 2 * 3: 8 rows, 7 swatches and "+43 more".
        let red = few.rgb.iter().filter(|c| **c == [1.0, 0.0, 0.0]).count();
        assert_eq!(red, 7 * 10 * 10);
    }
}
