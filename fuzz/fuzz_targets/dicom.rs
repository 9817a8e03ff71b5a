//! The DICOM reader on arbitrary bytes: no panic, no abort, no allocation over
//! libFuzzer's -malloc_limit_mb, and every error message one line.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The reader takes a path: one scratch file per fuzzing process.
    thread_local! {
        static PATH: std::path::PathBuf =
            std::env::temp_dir().join(format!("glint-fuzz-dicom-{}.dcm", std::process::id()));
    }
    PATH.with(|path| {
        std::fs::write(path, data).expect("scratch file");
        let options = glint_io::ReadOptions {
            // A small voxel limit, so that a legitimate 2^31-voxel allocation is not
            // mistaken for a bug by the malloc limit.
            max_voxels: 1 << 22,
            ..glint_io::ReadOptions::default()
        };
        if let Err(e) = glint_io::dicom::read(path, &options) {
            let msg = e.to_string();
            assert!(
                !msg.contains('\n') && !msg.contains('\r'),
                "multi-line error: {msg:?}"
            );
        }
    });
});
