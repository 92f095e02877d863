//! Multibody model (immutable) and data (workspace).
