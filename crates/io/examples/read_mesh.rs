//! Reads a surface file and prints its vertex and triangle counts: the command the PLY
//! memory figures in docs/formats.md were measured with (`/usr/bin/time -v`).
fn main() {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("usage: read_mesh FILE");
        std::process::exit(2);
    };
    match glint_io::read_mesh(path.as_ref()) {
        Ok(m) => println!(
            "{} vertices, {} triangles",
            m.positions.len(),
            m.triangles.len()
        ),
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
