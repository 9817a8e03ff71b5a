//! The rules glint's tests share (issue 34), one copy for every crate:
//!
//! - **Strict mode** ([`strict`]): on when `GLINT_STRICT` or `CI` is set to a true
//!   value (anything but an empty string, `0`, `false`, `no` or `off`; the list is
//!   `false-values.txt`, which the pytest side reads too). In strict mode a missing
//!   tool or sample file fails the test, naming it; outside it the test says what is
//!   missing and returns. `scripts/test` (the README's test command) and `.ci/run`
//!   run strict.
//! - **Sample data** ([`data_dir`], [`sample`]): `$GLINT_DATA/samples`, by default
//!   `~/.cache/glint/samples` (what `scripts/fetch-samples` fills).
//! - **The record of optional paths** ([`ran`], [`skipped`]): a line per SIMD level or
//!   external tool that a test ran (or could not run), appended to the file named by
//!   `GLINT_PATHS_LOG`; `scripts/test` prints the summary at the end of a run so a
//!   reader sees that nothing was skipped.
//! - **The browser** ([`browser_tools`]): the headless Chromium, node and
//!   playwright-core that the browser tests of glint-view and glint-batch drive.
//! - **DICOM objects** (`dicom`, with the `dicom` feature): the image header and the
//!   writer the DICOM tests of glint-io and the CLI build their files with.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(feature = "dicom")]
pub mod dicom;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The values that leave strict mode off (besides an unset variable).
const FALSE_VALUES: &str = include_str!("../false-values.txt");

/// Whether the value of `GLINT_STRICT` or `CI` turns strict mode on: `None` (unset),
/// an empty string and the spellings in `false-values.txt` do not, anything else does.
pub fn is_true(value: Option<&str>) -> bool {
    let Some(v) = value else { return false };
    let v = v.trim();
    !v.is_empty()
        && !FALSE_VALUES
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .any(|f| f.eq_ignore_ascii_case(v))
}

/// Whether this run is strict: `GLINT_STRICT` or `CI` is true (see [`is_true`]).
pub fn strict() -> bool {
    ["GLINT_STRICT", "CI"]
        .iter()
        .any(|k| is_true(std::env::var(k).ok().as_deref()))
}

/// `$GLINT_DATA`, by default `~/.cache/glint`: the directory scripts/fetch-samples
/// fills (its `samples/` subdirectory).
pub fn data_dir() -> PathBuf {
    std::env::var_os("GLINT_DATA")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(std::env::var_os("HOME").unwrap_or_default()).join(".cache/glint")
        })
}

/// The sample directory, `data_dir()/samples`.
pub fn samples_dir() -> PathBuf {
    data_dir().join("samples")
}

/// The sample file `name` (a path under [`samples_dir`]), or `None` after saying it
/// is missing; in strict mode a missing sample panics, naming it.
pub fn sample(name: &str) -> Option<PathBuf> {
    let path = samples_dir().join(name);
    if path.exists() {
        return Some(path);
    }
    missing(&format!(
        "sample {} (run scripts/fetch-samples, or set GLINT_DATA)",
        path.display()
    ));
    None
}

/// Reports that `what` (a tool or a file a test needs) is missing: in strict mode a
/// panic naming it, otherwise a note on stderr and a `SKIPPED` line in the record.
pub fn missing(what: &str) {
    assert!(
        !strict(),
        "missing: {what} (strict mode: GLINT_STRICT or CI is set)"
    );
    eprintln!("SKIPPED: missing {what} (set GLINT_STRICT=1 to make this a failure)");
    record(&format!("SKIPPED {what}"));
}

/// Whether a browser test can run: Debian's Chromium (`$CHROMIUM`, by default
/// `/usr/bin/chromium`; scripts/install-deps), `node`, and playwright-core installed
/// by `npm ci` in `browser_dir` (crates/view/browser). What is missing is reported by
/// [`missing`]: in strict mode the test fails, naming it.
pub fn browser_tools(browser_dir: &Path) -> bool {
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    let missing_tools: Vec<&str> = [
        (
            !Path::new(&chromium).exists(),
            "chromium (scripts/install-deps)",
        ),
        (
            Command::new("node").arg("--version").output().is_err(),
            "node",
        ),
        (
            !browser_dir.join("node_modules/playwright-core").is_dir(),
            "playwright-core (npm ci in crates/view/browser)",
        ),
    ]
    .into_iter()
    .filter_map(|(gone, what)| gone.then_some(what))
    .collect();
    if missing_tools.is_empty() {
        return true;
    }
    missing(&missing_tools.join(", "));
    false
}

/// Records that the optional path `what` ran (a SIMD level, an external tool).
pub fn ran(what: &str) {
    record(&format!("ran {what}"));
}

/// Records that the optional path `what` could not run here for a reason that is not
/// a defect (`why`: the CPU lacks the instructions, say).
pub fn skipped(what: &str, why: &str) {
    eprintln!("not run: {what} ({why})");
    record(&format!("not run {what} ({why})"));
}

/// Appends one line to the file named by `GLINT_PATHS_LOG`, if set. One `write` per
/// line on a file opened for appending, so lines of parallel tests do not interleave.
fn record(line: &str) {
    let Some(path) = std::env::var_os("GLINT_PATHS_LOG").filter(|p| !p.is_empty()) else {
        return;
    };
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path);
    let ok = file.and_then(|mut f| f.write_all(format!("{line}\n").as_bytes()));
    if let Err(e) = ok {
        panic!(
            "cannot append to GLINT_PATHS_LOG {}: {e}",
            PathBuf::from(path).display()
        );
    }
}

/// Copies the directory tree `from` to `to` (created), e.g. a test store to edit in a
/// temporary directory. Panics on an I/O error (test set-up).
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn true_and_false_spellings() {
        for v in ["1", "true", "TRUE", "yes", "on", " 1 ", "anything"] {
            assert!(is_true(Some(v)), "{v:?}");
        }
        for v in [
            None,
            Some(""),
            Some(" "),
            Some("0"),
            Some("false"),
            Some("False"),
        ] {
            assert!(!is_true(v), "{v:?}");
        }
        for v in ["no", "NO", "off", "Off"] {
            assert!(!is_true(Some(v)), "{v:?}");
        }
    }

    #[test]
    fn the_shared_list_has_exactly_the_documented_values() {
        // The module docs and the pytest side promise these four: a line added to
        // the file without updating them fails here.
        let values: Vec<&str> = FALSE_VALUES
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .collect();
        assert_eq!(values, ["0", "false", "no", "off"]);
    }
}
