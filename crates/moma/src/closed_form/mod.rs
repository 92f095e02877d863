//! The chapter's robots (m1–m5) in their own coordinates, closed form.
