//! The workspace-hack crate, generated and kept by `cargo hakari` (guppy's tool for it):
//! every workspace crate depends on it, and it names each third-party dependency with the
//! union of the features the whole workspace (dev-dependencies included) turns on. So
//! `cargo build -p glint-cli`, maturin's `cargo rustc -p glint-python` and `cargo test
//! --workspace` resolve the same features and share one compiled copy of each dependency
//! instead of compiling it once per feature set (the CI run compiled the workspace three
//! times). After a dependency change: `cargo hakari generate && cargo hakari manage-deps`.
