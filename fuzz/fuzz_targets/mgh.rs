//! Fuzzes the MGH/MGZ reader: any bytes must give a volume/mesh or a one-line error, never a
//! panic, an abort or an allocation beyond the input's size times a small factor.
#![no_main]

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = common::input_file(data, "mgz");
    common::check_error(glint_io::mgh::read(&path, &common::options()));
});
