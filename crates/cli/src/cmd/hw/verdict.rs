//! `glint hw verdict`: docs/hardware.md's verdict computed from a `pareto.csv` (see
//! `glint_hw::pareto::verdict`).

use std::path::PathBuf;

use anyhow::{bail, Context};
use glint_hw::pareto::{
    self,
    verdict::{between_markers, verdict_markdown, BEGIN_MARKER, END_MARKER},
};

/// Arguments of `glint hw verdict`.
#[derive(clap::Args)]
pub struct VerdictArgs {
    /// The pareto.csv to read.
    #[arg(long)]
    pub csv: PathBuf,
    /// Fail unless this Markdown file holds the verdict between its markers.
    #[arg(long, conflicts_with = "write")]
    pub check: Option<PathBuf>,
    /// Replace the text between the markers of this Markdown file with the verdict
    /// (atomically; the file must already hold both markers).
    #[arg(long)]
    pub write: Option<PathBuf>,
}

/// Largest Markdown file read.
const MAX_DOC_BYTES: u64 = 16 << 20;

fn read_doc(path: &std::path::Path) -> anyhow::Result<String> {
    let len = std::fs::metadata(path)
        .with_context(|| format!("reading {}", path.display()))?
        .len();
    if len > MAX_DOC_BYTES {
        bail!("{}: {len} bytes, more than {MAX_DOC_BYTES}", path.display());
    }
    std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))
}

/// Runs `glint hw verdict`.
pub fn run(args: VerdictArgs) -> anyhow::Result<()> {
    let rows = pareto::read_csv(&args.csv)?;
    let text = verdict_markdown(&rows)?;
    if let Some(doc) = &args.check {
        let held = read_doc(doc)?;
        let Some(held) = between_markers(&held) else {
            bail!(
                "{}: no verdict markers ({BEGIN_MARKER} ... {END_MARKER})",
                doc.display()
            );
        };
        if held != text.trim_matches('\n') {
            bail!(
                "{}: the verdict differs from {}'s (rerun with --write)",
                doc.display(),
                args.csv.display()
            );
        }
        outln!(
            "{}: the verdict matches {}",
            doc.display(),
            args.csv.display()
        )?;
        return Ok(());
    }
    if let Some(doc) = &args.write {
        let held = read_doc(doc)?;
        let (Some(a), Some(_)) = (held.find(BEGIN_MARKER), held.find(END_MARKER)) else {
            bail!(
                "{}: no verdict markers ({BEGIN_MARKER} ... {END_MARKER})",
                doc.display()
            );
        };
        let start = a + BEGIN_MARKER.len();
        let end = start
            + held[start..].find(END_MARKER).with_context(|| {
                format!("{}: {END_MARKER} before {BEGIN_MARKER}", doc.display())
            })?;
        let new = format!(
            "{}\n{}\n{}",
            &held[..start],
            text.trim_matches('\n'),
            &held[end..]
        );
        glint_io::write_atomic(doc, |w| w.write_all(new.as_bytes()))
            .with_context(|| format!("writing {}", doc.display()))?;
        outln!(
            "{}: verdict written from {}",
            doc.display(),
            args.csv.display()
        )?;
        return Ok(());
    }
    outln!("{}", text.trim_end())?;
    Ok(())
}
