//! glint-hw: placeholder, filled in by its issue.
