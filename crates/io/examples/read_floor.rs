//! The read floor of a study: reads each file named on the command line into memory
//! and inflates it when it is gzip (flate2's `MultiGzDecoder` with the zlib-rs backend,
//! the inflater glint's readers use), into a buffer sized from the gzip trailer, and
//! prints the bytes inflated. Nothing is parsed or converted: the least any reader of
//! these files must spend. `scripts/bench/bench-batch` times this process's CPU
//! seconds over the study's files beside `glint batch`'s (docs/performance.md).
use std::io::Read;

fn main() {
    let paths: Vec<_> = std::env::args_os().skip(1).collect();
    if paths.is_empty() {
        eprintln!("usage: read_floor FILE...");
        std::process::exit(2);
    }
    let mut total = 0u64;
    for path in paths {
        match floor(path.as_ref()) {
            Ok(n) => total += n,
            Err(e) => {
                eprintln!("{}: {e}", path.to_string_lossy());
                std::process::exit(1);
            }
        }
    }
    println!("{total}");
}

/// Reads `path` and inflates it if it is gzip; the bytes that came out.
fn floor(path: &std::path::Path) -> std::io::Result<u64> {
    let raw = std::fs::read(path)?;
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Ok(std::hint::black_box(raw).len() as u64);
    }
    // ISIZE, the last member's length modulo 2^32: a capacity hint only.
    let hint = raw
        .last_chunk::<4>()
        .map_or(0, |b| u32::from_le_bytes(*b) as usize);
    let mut out = Vec::with_capacity(hint);
    flate2::read::MultiGzDecoder::new(&raw[..]).read_to_end(&mut out)?;
    Ok(std::hint::black_box(out).len() as u64)
}
