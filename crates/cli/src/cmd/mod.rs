//! One module per subcommand.

pub mod analyze;
pub mod batch;
pub mod bench;
pub mod choice;
pub mod compare;
pub mod devices;
pub mod eval;
pub mod hw;
pub mod info;
pub mod info_labels;
pub mod label_flags;
pub mod mesh;
pub mod pick;
pub mod render;
pub mod scene_flags;
mod spinner;
pub mod tf;
pub mod view;
