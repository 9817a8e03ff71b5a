//! One module per subcommand.

pub mod analyze;
pub mod bench;
pub mod choice;
pub mod eval;
pub mod hw;
pub mod info;
pub mod render;
pub mod view;
