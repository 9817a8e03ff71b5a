//! With the `oidn` feature: the directory of libOpenImageDenoise (`$OIDN_DIR/lib`,
//! fetched by scripts/fetch-oidn; the `oidn` crate links from it) as the run path of
//! this crate's binaries, so they find the library without LD_LIBRARY_PATH.
fn main() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_OIDN").is_none() {
        return;
    }
    match std::env::var("OIDN_DIR") {
        Ok(dir) if !dir.is_empty() => {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}/lib");
        }
        _ => println!(
            "cargo:warning=the oidn feature needs OIDN_DIR: OIDN_DIR=$(scripts/fetch-oidn) cargo build --features oidn"
        ),
    }
}
