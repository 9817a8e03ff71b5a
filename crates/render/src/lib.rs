//! glint-render: placeholder, filled in by its issue.
