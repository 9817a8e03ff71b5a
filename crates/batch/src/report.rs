//! `index.html`: the static report of a study, one file with its style and script
//! inline, which a browser opens from the disk (no server, no network).

use std::fmt::Write as _;

use html_escape::{encode_double_quoted_attribute as attr, encode_text as text};

use crate::row::{Row, Status};

/// The report's style: a grid of cards, thumbnails scaled to the card.
const STYLE: &str = "\
body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;background:#fafafa;color:#222}\
h1{font-size:1.4em;margin:0 0 .3em}\
#controls{margin:.8em 0}#controls button{margin-right:.3em}\
button[aria-pressed=true]{font-weight:bold}\
#grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(380px,1fr));gap:12px}\
.card{background:#fff;border:1px solid #ddd;border-radius:6px;padding:8px}\
.card.failed{border-color:#c33;background:#fff5f5}\
.card h2{font-size:1em;margin:.2em 0;word-break:break-all}\
.thumb{width:100%;height:auto;background:#000;display:block;margin-bottom:4px}\
.meta,.path{color:#555;font-size:.9em;margin:.2em 0;word-break:break-all}\
.error{color:#a00;font-family:monospace;white-space:pre-wrap;word-break:break-word}\
.notes{margin:.2em 0;padding-left:1.2em;color:#555;font-size:.9em}\
body.only-failed .card.ok{display:none}";

/// The report's script: sorting the cards by a `data-` attribute (numbers inside
/// labels compared as numbers, ties by id) and hiding the inputs that succeeded.
const SCRIPT: &str = r##"
const grid = document.getElementById("grid");
const order = (a, b) => (a || "\uffff").localeCompare(b || "\uffff", undefined, {numeric: true});
function sortBy(key) {
  const cards = Array.from(grid.children);
  cards.sort((a, b) => order(a.dataset[key], b.dataset[key]) || order(a.dataset.id, b.dataset.id));
  for (const c of cards) grid.appendChild(c);
  for (const b of document.querySelectorAll("#controls button"))
    b.setAttribute("aria-pressed", String(b.dataset.sort === key));
}
for (const b of document.querySelectorAll("#controls button"))
  b.addEventListener("click", () => sortBy(b.dataset.sort));
document.getElementById("only-failed").addEventListener("change",
  (e) => document.body.classList.toggle("only-failed", e.target.checked));
"##;

/// The report of a study's rows (in the order given): a header with the counts, sort
/// buttons (subject, input, status) and a "failed only" filter, then a card per
/// input with its mosaic and slices as thumbnails (each a link to the full-size PNG,
/// relative to the report), its subject, session, volume and time, the reader's notes,
/// or its error. Thumbnails load lazily, so a study of thousands opens quickly.
pub fn report_html<'a>(rows: impl IntoIterator<Item = &'a Row>) -> String {
    let rows: Vec<&Row> = rows.into_iter().collect();
    let failed = rows.iter().filter(|r| r.status == Status::Failed).count();
    let views = rows.first().map(|r| r.views.join(", ")).unwrap_or_default();
    let mut html = String::with_capacity(2048 + 1024 * rows.len());
    let _ = write!(
        html,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width\">\
<title>glint batch: {n} inputs, {failed} failed</title><style>{STYLE}</style></head>\n<body>\n\
<h1>glint batch</h1>\n<p id=\"summary\">{n} inputs: <b>{ok}</b> made, <b>{failed}</b> failed. \
Views: {views}. Click a picture for its full size.</p>\n\
<div id=\"controls\">Sort by <button data-sort=\"subject\" aria-pressed=\"false\">subject</button>\
<button data-sort=\"id\" aria-pressed=\"true\">input</button>\
<button data-sort=\"status\" aria-pressed=\"false\">status</button> \
<label><input type=\"checkbox\" id=\"only-failed\"> failed only</label></div>\n<main id=\"grid\">\n",
        n = rows.len(),
        ok = rows.len() - failed,
        views = text(&views),
    );
    for row in &rows {
        card(&mut html, row);
    }
    let _ = write!(html, "</main>\n<script>{SCRIPT}</script>\n</body></html>\n");
    html
}

/// One input's card.
fn card(html: &mut String, row: &Row) {
    let status = match row.status {
        Status::Ok => "ok",
        Status::Failed => "failed",
    };
    let _ = writeln!(
        html,
        "<article class=\"card {status}\" id=\"row-{id}\" data-id=\"{id}\" data-subject=\"{subject}\" \
data-session=\"{session}\" data-status=\"{status}\">",
        id = attr(&row.id),
        subject = attr(row.subject.as_deref().unwrap_or("")),
        session = attr(row.session.as_deref().unwrap_or("")),
    );
    if let Some(o) = &row.outputs {
        for (file, what) in [(Some(&o.mosaic), "views"), (o.slices.as_ref(), "slices")] {
            if let Some(file) = file {
                let _ = writeln!(
                    html,
                    "<a href=\"{f}\"><img class=\"thumb {what}\" src=\"{f}\" loading=\"lazy\" \
alt=\"{id}: {what}\"></a>",
                    f = attr(file),
                    id = attr(&row.id),
                );
            }
        }
    }
    let _ = writeln!(html, "<h2>{}</h2>", text(&row.id));
    let mut meta = Vec::new();
    if let Some(s) = &row.subject {
        meta.push(format!("subject {s}"));
    }
    if let Some(s) = &row.session {
        meta.push(format!("session {s}"));
    }
    if let Some(v) = &row.volume {
        let [x, y, z] = v.dims;
        let [a, b, c] = v.spacing;
        meta.push(format!("{x}×{y}×{z}, {a:.3}×{b:.3}×{c:.3} mm"));
    }
    if let Some(s) = &row.seconds {
        meta.push(format!("{:.2} s", s.total));
    }
    if !meta.is_empty() {
        let _ = writeln!(html, "<p class=\"meta\">{}</p>", text(&meta.join(" · ")));
    }
    let _ = writeln!(html, "<p class=\"path\">{}</p>", text(&row.input));
    if let Some(e) = &row.error {
        let _ = writeln!(html, "<p class=\"error\">{}</p>", text(e));
    }
    if !row.notes.is_empty() {
        html.push_str("<ul class=\"notes\">");
        for n in &row.notes {
            let _ = write!(html, "<li>{}</li>", text(n));
        }
        html.push_str("</ul>\n");
    }
    html.push_str("</article>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::Outputs;
    use crate::Item;

    fn item(id: &str, subject: Option<&str>) -> Item {
        Item {
            id: id.into(),
            path: format!("/study/{id}.nii.gz").into(),
            subject: subject.map(String::from),
            session: None,
        }
    }

    #[test]
    fn cards_show_pictures_notes_and_escaped_errors() {
        let views = vec!["left".to_string()];
        let mut good = Row::failed(
            &item("sub-01_T1w", Some("01")),
            "k",
            &views,
            None,
            "x".into(),
        );
        good.status = Status::Ok;
        good.error = None;
        good.outputs = Some(Outputs {
            mosaic: "sub-01_T1w/mosaic.png".into(),
            slices: Some("sub-01_T1w/slices.png".into()),
            scene: "sub-01_T1w/scene.json".into(),
        });
        good.notes = vec!["affine from sform".into()];
        let bad = Row::failed(
            &item("broken", None),
            "k",
            &views,
            None,
            "broken.nii: bad magic <\"&>".into(),
        );
        let html = report_html([&good, &bad]);
        assert_eq!(html.matches("<img class=\"thumb").count(), 2);
        assert!(html.contains("src=\"sub-01_T1w/mosaic.png\""));
        assert!(html.contains("<li>affine from sform</li>"));
        assert!(html.contains("bad magic &lt;\"&amp;&gt;"), "{html}");
        assert!(html.contains("class=\"card failed\" id=\"row-broken\""));
        assert!(html.contains("data-subject=\"01\""));
        assert!(html.contains("1 failed"));
        // Self-contained: nothing fetched from elsewhere.
        assert!(!html.contains("http:") && !html.contains("https:") && !html.contains("//cdn"));
    }
}
