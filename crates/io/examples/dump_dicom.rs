//! Reads a DICOM file or directory and writes its samples as raw little-endian values
//! (colour: R G B interleaved, one value each) in glint's order (x fastest, slices along
//! the normal): the command the lossy-JPEG differences in docs/formats.md were measured
//! with, against pydicom's decode of the same file (scripts/fixtures/pydicom-table.py's venv).
//!
//! Usage: dump_dicom FILE OUT.raw   (prints dims, type and whether it is colour)
use glint_io::{ReadOptions, Samples};

fn bytes(s: &Samples, i: usize) -> Vec<u8> {
    match s {
        Samples::U8(v) => vec![v[i]],
        Samples::U16(v) => v[i].to_le_bytes().to_vec(),
        Samples::U32(v) => v[i].to_le_bytes().to_vec(),
        Samples::I8(v) => v[i].to_le_bytes().to_vec(),
        Samples::I16(v) => v[i].to_le_bytes().to_vec(),
        Samples::I32(v) => v[i].to_le_bytes().to_vec(),
        Samples::F32(v) => v[i].to_le_bytes().to_vec(),
        Samples::F64(v) => v[i].to_le_bytes().to_vec(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 3 {
        eprintln!("usage: dump_dicom FILE OUT.raw");
        std::process::exit(2);
    }
    let v = match glint_io::dicom::read(args[1].as_ref(), &ReadOptions::default()) {
        Ok(f) => f.volume,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let mut out = Vec::new();
    for i in 0..v.len() {
        match &v.colour {
            Some(rgb) => rgb.channels().iter().for_each(|c| out.extend(bytes(c, i))),
            None => out.extend(bytes(&v.samples, i)),
        }
    }
    if let Err(e) = std::fs::write(&args[2], out) {
        eprintln!("{}: {e}", args[2]);
        std::process::exit(1);
    }
    println!(
        "{:?} {} {}",
        v.dims,
        v.samples.type_name(),
        if v.colour.is_some() { "colour" } else { "grey" }
    );
}
