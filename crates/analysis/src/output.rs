//! All-or-nothing output: files are written into a staging directory beside (or
//! inside) the target and renamed into place only once every file is complete.

use std::fs;
use std::path::{Path, PathBuf};

use tempfile::TempDir;

use crate::error::AnalysisError;

fn io(what: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> AnalysisError {
    let path = path.to_path_buf();
    move |source| AnalysisError::Io { what, path, source }
}

/// A staging directory for the files of one output directory.
#[derive(Debug)]
pub struct Staging {
    tmp: TempDir,
    target: PathBuf,
}

impl Staging {
    /// Prepares to write into `target`. The target must be a directory or not exist; its
    /// parent must exist. Nothing is visible in `target` until [`Staging::commit`].
    pub fn new(target: &Path) -> Result<Self, AnalysisError> {
        let refuse = |reason: &str| AnalysisError::Output {
            path: target.to_path_buf(),
            reason: reason.to_string(),
        };
        if target.as_os_str().is_empty() {
            return Err(refuse("the output directory is an empty path"));
        }
        let tmp = if target.exists() {
            if !target.is_dir() {
                return Err(refuse("it exists and is not a directory"));
            }
            tempfile::Builder::new()
                .prefix(".glint-staging-")
                .tempdir_in(target)
        } else {
            let parent = match target.parent() {
                Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                _ => PathBuf::from("."),
            };
            if !parent.is_dir() {
                return Err(refuse(&format!(
                    "its parent {} does not exist or is not a directory",
                    parent.display()
                )));
            }
            let name = target
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "out".into());
            tempfile::Builder::new()
                .prefix(&format!(".{name}.glint-staging-"))
                .tempdir_in(&parent)
        }
        .map_err(|e| refuse(&format!("cannot create a staging directory there ({e})")))?;
        Ok(Staging {
            tmp,
            target: target.to_path_buf(),
        })
    }

    /// The staging directory: write every file here.
    pub fn path(&self) -> &Path {
        self.tmp.path()
    }

    /// Writes one file (relative path) into the staging directory.
    pub fn write(&self, rel: &str, bytes: &[u8]) -> Result<(), AnalysisError> {
        let path = self.tmp.path().join(rel);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(io("creating", parent))?;
        }
        fs::write(&path, bytes).map_err(io("writing", &path))
    }

    /// Moves every staged file into the target. A new target is one rename; into an
    /// existing directory each file is renamed over its old version (never a partly
    /// written file). Returns the final paths of the files.
    pub fn commit(self) -> Result<Vec<PathBuf>, AnalysisError> {
        let mut rel = Vec::new();
        list_files(self.tmp.path(), Path::new(""), &mut rel)?;
        rel.sort();
        if !self.target.exists() {
            fs::rename(self.tmp.path(), &self.target).map_err(io("renaming into", &self.target))?;
            // The directory now lives at the target: do not delete it.
            let _ = self.tmp.keep();
        } else {
            for r in &rel {
                let to = self.target.join(r);
                if let Some(parent) = to.parent() {
                    fs::create_dir_all(parent).map_err(io("creating", parent))?;
                }
                fs::rename(self.tmp.path().join(r), &to).map_err(io("renaming into", &to))?;
            }
        }
        Ok(rel.iter().map(|r| self.target.join(r)).collect())
    }
}

fn list_files(root: &Path, rel: &Path, out: &mut Vec<PathBuf>) -> Result<(), AnalysisError> {
    let dir = root.join(rel);
    for entry in fs::read_dir(&dir).map_err(io("listing", &dir))? {
        let entry = entry.map_err(io("listing", &dir))?;
        let r = rel.join(entry.file_name());
        if entry.path().is_dir() {
            list_files(root, &r, out)?;
        } else {
            out.push(r);
        }
    }
    Ok(())
}
