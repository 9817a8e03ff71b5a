//! Fuzzes the OME-Zarr reader's metadata: the input is split at its first two NUL bytes
//! into a Zarr v3 group's `zarr.json` (the OME `multiscales` attributes), the array
//! `0/zarr.json` (shape, chunk grid, codecs, fill value) and the bytes of chunk
//! `0/c/0/0/0`; any input must give a volume or a one-line error, never a panic, an
//! abort or an allocation sized by the metadata beyond the reader's voxel limit.
#![no_main]

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut parts = data.splitn(3, |&b| b == 0);
    let group = parts.next().unwrap_or_default();
    let array = parts.next().unwrap_or_default();
    let chunk = parts.next().unwrap_or_default();
    let store = common::input_dir("zarr");
    let _ = std::fs::remove_dir_all(&store);
    std::fs::create_dir_all(store.join("0/c/0/0")).expect("create the store");
    std::fs::write(store.join("zarr.json"), group).expect("write the group");
    std::fs::write(store.join("0/zarr.json"), array).expect("write the array");
    std::fs::write(store.join("0/c/0/0/0"), chunk).expect("write the chunk");
    common::check_error(glint_io::zarr::levels(&store));
    common::check_error(glint_io::zarr::read(&store, &common::options()));
});
