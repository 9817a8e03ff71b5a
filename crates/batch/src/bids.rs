//! BIDS apps' conventions: choosing participants and sessions, and the output folder as
//! a BIDS derivatives dataset (BIDS 1.9, "Derived dataset and pipeline description"),
//! as fMRIPrep and MRIQC write theirs.

use std::path::Path;

use serde_json::json;

use crate::{BatchError, Item};

/// The BIDS version the derivatives description follows.
pub const BIDS_VERSION: &str = "1.9.0";

/// The file that makes a folder a BIDS dataset.
pub const DESCRIPTION_FILE: &str = "dataset_description.json";

/// Which participants and sessions of a study to make (`--participant-label`,
/// `--session-label`); empty lists take all. Labels are given with or without their
/// `sub-` or `ses-` prefix, as BIDS apps take them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Selection {
    /// Subject labels (`01` or `sub-01`).
    pub participants: Vec<String>,
    /// Session labels (`pre` or `ses-pre`).
    pub sessions: Vec<String>,
}

impl Selection {
    /// Whether the selection takes every input.
    pub fn is_empty(&self) -> bool {
        self.participants.is_empty() && self.sessions.is_empty()
    }
}

/// The items of the participants and sessions `selection` names, in their order. A
/// label that no input carries is an error naming the labels there are (a typo must
/// not run a study without the subject it meant), and so is a selection that leaves
/// nothing.
pub fn select(items: Vec<Item>, selection: &Selection) -> Result<Vec<Item>, BatchError> {
    if selection.is_empty() {
        return Ok(items);
    }
    let participants = labels(&selection.participants, "sub-");
    let sessions = labels(&selection.sessions, "ses-");
    present(&items, &participants, "participant", |i| {
        i.subject.as_deref()
    })?;
    present(&items, &sessions, "session", |i| i.session.as_deref())?;
    let keep = |label: &Option<String>, wanted: &[String]| {
        wanted.is_empty() || label.as_ref().is_some_and(|l| wanted.contains(l))
    };
    let chosen: Vec<Item> = items
        .into_iter()
        .filter(|i| keep(&i.subject, &participants) && keep(&i.session, &sessions))
        .collect();
    if chosen.is_empty() {
        return Err(BatchError::NoInputs(format!(
            "no input of participant(s) {} in session(s) {}",
            participants.join(", "),
            sessions.join(", ")
        )));
    }
    Ok(chosen)
}

/// Refuses a wanted label that no item carries, naming those there are.
fn present(
    items: &[Item],
    wanted: &[String],
    what: &str,
    label: fn(&Item) -> Option<&str>,
) -> Result<(), BatchError> {
    let mut there: Vec<&str> = items.iter().filter_map(label).collect();
    there.sort_unstable();
    there.dedup();
    match wanted.iter().find(|w| !there.contains(&w.as_str())) {
        None => Ok(()),
        Some(missing) => Err(BatchError::NoInputs(format!(
            "no input of {what} label '{missing}' (the inputs have {})",
            if there.is_empty() {
                "none".to_string()
            } else {
                there.join(", ")
            }
        ))),
    }
}

/// Labels without their entity prefix.
fn labels(given: &[String], prefix: &str) -> Vec<String> {
    given
        .iter()
        .map(|l| l.trim())
        .map(|l| l.strip_prefix(prefix).unwrap_or(l).to_string())
        .collect()
}

/// Whether `dir` is a BIDS dataset (it holds `dataset_description.json`).
pub fn is_dataset(dir: &Path) -> bool {
    dir.join(DESCRIPTION_FILE).is_file()
}

/// What made a derivatives dataset: the `GeneratedBy` entry of its description.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GeneratedBy {
    /// The pipeline's name (`glint`).
    pub name: String,
    /// Its version.
    pub version: String,
    /// The command line that ran it.
    pub command: String,
}

/// Writes `out/dataset_description.json` (atomically) that makes the output folder a
/// BIDS derivatives dataset: `Name`, `BIDSVersion`, `DatasetType: "derivative"`,
/// `GeneratedBy` (name, version, and the command as its `Description`) and
/// `SourceDatasets` (the BIDS datasets read, as `file://` URLs of their absolute
/// paths).
pub fn write_description(
    out: &Path,
    by: &GeneratedBy,
    sources: &[&Path],
) -> Result<(), BatchError> {
    let sources: Vec<_> = sources
        .iter()
        .map(|p| {
            let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
            json!({ "URL": format!("file://{}", abs.display()) })
        })
        .collect();
    let description = json!({
        "Name": format!("{} renders", by.name),
        "BIDSVersion": BIDS_VERSION,
        "DatasetType": "derivative",
        "GeneratedBy": [{
            "Name": by.name,
            "Version": by.version,
            "Description": by.command,
        }],
        "SourceDatasets": sources,
    });
    let text = serde_json::to_string_pretty(&description).expect("JSON of strings") + "\n";
    glint_io::write_atomic(&out.join(DESCRIPTION_FILE), |w| {
        w.write_all(text.as_bytes())
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(id: &str, subject: Option<&str>, session: Option<&str>) -> Item {
        Item {
            id: id.into(),
            path: format!("/d/{id}.nii.gz").into(),
            subject: subject.map(Into::into),
            session: session.map(Into::into),
        }
    }

    fn ids(items: &[Item]) -> Vec<&str> {
        items.iter().map(|i| i.id.as_str()).collect()
    }

    #[test]
    fn participants_and_sessions_are_chosen_with_or_without_their_prefix() {
        let items = vec![
            item("a", Some("01"), Some("pre")),
            item("b", Some("01"), Some("post")),
            item("c", Some("02"), Some("pre")),
            item("d", Some("03"), None),
        ];
        let pick = |p: &[&str], s: &[&str]| {
            let sel = Selection {
                participants: p.iter().map(|x| x.to_string()).collect(),
                sessions: s.iter().map(|x| x.to_string()).collect(),
            };
            select(items.clone(), &sel)
        };
        assert_eq!(ids(&pick(&[], &[]).unwrap()), ["a", "b", "c", "d"]);
        assert_eq!(ids(&pick(&["sub-01", "03"], &[]).unwrap()), ["a", "b", "d"]);
        assert_eq!(ids(&pick(&[], &["ses-pre"]).unwrap()), ["a", "c"]);
        assert_eq!(ids(&pick(&["01"], &["post"]).unwrap()), ["b"]);
        let e = pick(&["04"], &[]).unwrap_err().to_string();
        assert_eq!(
            e,
            "no inputs: no input of participant label '04' (the inputs have 01, 02, 03)"
        );
        let e = pick(&["03"], &["pre"]).unwrap_err().to_string();
        assert!(
            e.contains("no input of participant(s) 03 in session(s) pre"),
            "{e}"
        );
    }

    #[test]
    fn the_description_makes_a_derivatives_dataset() {
        let dir = tempfile::tempdir().unwrap();
        let by = GeneratedBy {
            name: "glint".into(),
            version: "0.1.0".into(),
            command: "glint batch ds -o out".into(),
        };
        write_description(dir.path(), &by, &[Path::new("/data/ds")]).unwrap();
        let text = std::fs::read_to_string(dir.path().join(DESCRIPTION_FILE)).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["DatasetType"], "derivative");
        assert_eq!(v["BIDSVersion"], "1.9.0");
        assert_eq!(v["GeneratedBy"][0]["Name"], "glint");
        assert_eq!(v["GeneratedBy"][0]["Version"], "0.1.0");
        assert_eq!(v["GeneratedBy"][0]["Description"], "glint batch ds -o out");
        assert_eq!(v["SourceDatasets"][0]["URL"], "file:///data/ds");
        assert!(is_dataset(dir.path()));
    }
}
