//! Errors as the one line a front end prints.

/// The error and its sources joined with `": "`, on one line (newlines inside a
/// message become spaces): what `glint` prints after `glint: error: ` (anyhow's `{:#}`
/// format), and what the viewer and the Python module report, so every front end
/// names the same cause the same way.
///
/// ```
/// let inner = std::io::Error::other("disk full");
/// let outer = glint_io::IoError::Os { path: "a.nii".into(), source: inner };
/// assert_eq!(glint_io::one_line(&outer), format!("{outer}: disk full"));
/// ```
pub fn one_line(err: &dyn std::error::Error) -> String {
    let mut line = err.to_string();
    let mut source = err.source();
    while let Some(s) = source {
        line.push_str(": ");
        line.push_str(&s.to_string());
        source = s.source();
    }
    line.replace('\n', " ")
}
