//! `glint render` of colour volumes: drawn in the data's colours by default, grey
//! through the transfer function with `--channel` (issue 33).

use std::path::Path;
use std::process::Command;

use dicom_core::value::PrimitiveValue;
use dicom_core::VR;
use dicom_dictionary_std::tags;
use glint_testkit::dicom::{ds, put, write, ImageHeader, EXPLICIT_LE, SC_TRUE_COLOR};

const SIDE: usize = 16;
const FRAMES: usize = 8;

/// A 16x16, 8-frame RGB image (interleaved, 8-bit): a box of columns and rows 3..13 in
/// frames 1..7, pure red where the column is below 8 and pure blue from 8 on, black
/// elsewhere.
fn write_halves(path: &Path) {
    let mut o = ImageHeader {
        class: SC_TRUE_COLOR,
        modality: "OT",
        frames: Some(FRAMES as u32),
        samples: 3,
        photometric: "RGB",
        bits: 8,
        ..ImageHeader::ct(SIDE as u16, SIDE as u16)
    }
    .object();
    put(
        &mut o,
        tags::PLANAR_CONFIGURATION,
        VR::US,
        PrimitiveValue::from(0u16),
    );
    put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&[1.0, 1.0]));
    put(&mut o, tags::SPACING_BETWEEN_SLICES, VR::DS, ds(&[1.0]));
    let mut px = Vec::with_capacity(SIDE * SIDE * FRAMES * 3);
    for f in 0..FRAMES {
        for y in 0..SIDE {
            for x in 0..SIDE {
                let inside = (3..13).contains(&x) && (3..13).contains(&y) && (1..7).contains(&f);
                px.extend(match (inside, x < 8) {
                    (false, _) => [0, 0, 0],
                    (true, true) => [255, 0, 0],
                    (true, false) => [0, 0, 255],
                });
            }
        }
    }
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OB,
        PrimitiveValue::U8(px.into()),
    );
    write(path, o, SC_TRUE_COLOR, EXPLICIT_LE);
}

/// A white transfer function, opaque above luma 20 (the box's red is 76, its blue
/// 29, BT.601), lit diffusely (no specular white): any hue in the image is the data's.
const WHITE_TF: &str = r#"{"opacity": [[0, 0], [10, 0], [20, 1], [255, 1]],
 "color": [[0, 1, 1, 1], [255, 1, 1, 1]],
 "ambient": 0.2, "diffuse": 0.8, "specular": 0.0, "power": 10}"#;

/// Renders `input` at 48x48 with `args`; returns the 8-bit RGB pixels, after
/// checking the command succeeded.
fn render(input: &Path, tf: &Path, args: &[&str], out: &Path) -> Vec<[u8; 3]> {
    let run = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", "-q", "--size", "48x48", "--tf"])
        .arg(tf)
        .args(args)
        .arg("-o")
        .arg(out)
        .arg(input)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(out).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut px = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut px).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let channels = info.color_type.samples();
    px.chunks(channels).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Mean over the pixels of max - min channel: 0 for a grey image.
fn mean_chroma(px: &[[u8; 3]]) -> f64 {
    let sum: u64 = px
        .iter()
        .map(|c| u64::from(c.iter().max().unwrap() - c.iter().min().unwrap()))
        .sum();
    sum as f64 / px.len() as f64
}

#[test]
fn a_colour_volume_renders_in_its_colours_and_grey_with_a_channel() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("halves.dcm");
    write_halves(&input);
    let tf = dir.path().join("white.json");
    std::fs::write(&tf, WHITE_TF).unwrap();
    let px = render(&input, &tf, &[], &dir.path().join("colour.png"));
    let (mut red, mut blue, mut other) = (0, 0, 0);
    for c in &px {
        // Shading scales the value, not the hue: no green anywhere.
        assert!(c[1] <= 1, "green in {c:?}");
        match (c[0] > 20, c[2] > 20) {
            (true, false) if c[2] <= 1 => red += 1,
            (false, true) if c[0] <= 1 => blue += 1,
            (false, false) => {}
            _ => other += 1,
        }
    }
    // Both halves, about as large; mixed (magenta) only where they meet.
    assert!(red > 200 && blue > 200, "{red} red, {blue} blue");
    let shown = red + blue + other;
    assert!(other * 100 < 20 * shown, "{other} of {shown} mixed");

    // One channel: grey, through the white transfer function (the camera frames
    // what the channel makes visible: the red channel shows the red half only, the
    // blue channel the blue half, the luma both, each filling the frame).
    for channel in ["r", "b", "luma"] {
        let grey = render(
            &input,
            &tf,
            &["--channel", channel],
            &dir.path().join("g.png"),
        );
        assert!(
            grey.iter().all(|c| c[0] == c[1] && c[1] == c[2]),
            "{channel}"
        );
        let lit = grey.iter().filter(|c| c[0] > 20).count();
        assert!(lit > 200, "{channel}: {lit} lit");
    }
}

#[test]
fn colour_files_from_pydicom_render_in_colour() {
    let dir = tempfile::tempdir().unwrap();
    let tf = dir.path().join("white.json");
    std::fs::write(&tf, WHITE_TF).unwrap();
    // RLE RGB, 8 bits, and native RGB, 32 bits: colour bars; a YBR_FULL_422
    // ultrasound cine (30 frames): a grey echo with a few coloured marks (its mean
    // chroma 0.25 of 255 at this size, measured).
    for (name, min_chroma) in [
        ("pydicom/SC_rgb_rle_2frame.dcm", 5.0),
        ("pydicom-data/SC_rgb_32bit_2frame.dcm", 5.0),
        ("pydicom/examples_ybr_color.dcm", 0.1),
    ] {
        let Some(input) = glint_testkit::sample(name) else {
            continue;
        };
        let view = ["--view", "superior"];
        let px = render(&input, &tf, &view, &dir.path().join("c.png"));
        let chroma = mean_chroma(&px);
        assert!(chroma > min_chroma, "{name}: mean chroma {chroma}");
        let args = [&view[..], &["--channel", "luminance"]].concat();
        let grey = render(&input, &tf, &args, &dir.path().join("g.png"));
        assert_eq!(mean_chroma(&grey), 0.0, "{name}");
    }
}
