//! The viewer's split frames against the two renders they combine (issue 34): the
//! side-by-side frame is the exact render on the left and the chosen lobe's on the
//! right, pixel for pixel; the difference frame is the heat map of their luminance
//! difference, recomputed here from the two renders with the Rec. 709 weights (the map's
//! ramps are sRGB values, so the 8-bit frame shows them as they are), and it is not
//! black where they differ. Frames are the
//! lossless PNG the viewer saves (`Purpose::Save`).

use glint_lobe::LobeKind;
use glint_render::{LobeSpec, Phantom, ReadOptions, Renderer, Scene};
use glint_view::protocol::{FrameHeader, Purpose, Split};
use glint_view::render_frame;

/// Full heat of the difference view: 5% of linear luminance (session.rs's scale; the
/// viewer's help text states it too).
const FULL_SCALE: f64 = 0.05;

fn scene() -> Scene {
    Scene {
        // K_2 at n = 200 is far from cos^200, so the two renders differ.
        lobe: LobeSpec {
            kind: LobeKind::EnergyFit.into(),
            n: Some(200.0),
            v: 2,
            ..LobeSpec::default()
        },
        ..Scene::phantom(Phantom::SheppLogan, 32, [40, 32])
    }
}

/// A PNG's 8-bit RGB pixels, width and height.
fn decode(png_bytes: &[u8]) -> (usize, usize, Vec<[u8; 3]>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(png_bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let channels = info.color_type.samples();
    let px = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width as usize, info.height as usize, px)
}

/// The viewer's frame of `split`, decoded.
fn frame(r: &mut Renderer, split: Split) -> (usize, usize, Vec<[u8; 3]>) {
    let f = render_frame(r, &scene(), split, Purpose::Save, 1).unwrap();
    let (h, png_bytes) = FrameHeader::decode(&f.message).unwrap();
    let d = decode(png_bytes);
    assert_eq!((h.width as usize, h.height as usize), (d.0, d.1));
    d
}

#[test]
fn side_by_side_is_exact_left_and_the_lobe_right() {
    let mut r = Renderer::open(&scene(), &ReadOptions::default()).unwrap();
    let main = r.render(&scene(), &|_| {}).unwrap();
    let exact = r.render(&main.scene.with_exact_lobe(), &|_| {}).unwrap();
    let (_, _, left) = decode(&exact.image.encode_png(glint_render::Depth::Eight).unwrap());
    let (_, _, right) = decode(&main.image.encode_png(glint_render::Depth::Eight).unwrap());
    assert_ne!(
        left, right,
        "the two renders must differ for the check to mean much"
    );
    let (w, h, px) = frame(&mut r, Split::Side);
    assert_eq!((w, h), (80, 32));
    for y in 0..h {
        for x in 0..40 {
            assert_eq!(px[y * w + x], left[y * 40 + x], "left ({x}, {y})");
            assert_eq!(px[y * w + 40 + x], right[y * 40 + x], "right ({x}, {y})");
        }
    }
}

#[test]
fn difference_is_the_heat_map_of_the_two_renders() {
    let mut r = Renderer::open(&scene(), &ReadOptions::default()).unwrap();
    let main = r.render(&scene(), &|_| {}).unwrap();
    let exact = r.render(&main.scene.with_exact_lobe(), &|_| {}).unwrap();
    let (w, h, px) = frame(&mut r, Split::Diff);
    assert_eq!((w, h), (40, 32));
    // Rec. 709 luminance of linear RGB (ITU-R BT.709 item 3.2).
    let lum = |c: [f32; 3]| {
        0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
    };
    let mut hot = 0;
    for (i, p) in px.iter().enumerate() {
        let d = (lum(exact.image.rgb[i]) - lum(main.image.rgb[i])).abs();
        let t = (d / FULL_SCALE).min(1.0) * 3.0;
        // Black, red, yellow, white: the sRGB ramps of red, then green, then blue.
        for (c, &got) in p.iter().enumerate() {
            let want = (t - c as f64).clamp(0.0, 1.0) * 255.0;
            // The frame went linear and back through 8 bits: within one step.
            assert!(
                (f64::from(got) - want).abs() <= 1.0,
                "pixel {i} channel {c}: {got} vs {want:.2} (difference {d})"
            );
        }
        hot += usize::from(p[0] > 0);
    }
    assert!(hot > 0, "the renders differ, so the map is not black");
}
