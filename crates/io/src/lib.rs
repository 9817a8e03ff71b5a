//! glint-io: placeholder, filled in by its issue.
