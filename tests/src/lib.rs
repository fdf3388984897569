//! Tests that span crates live in `tests/tests/`.

pub mod reproduce;
pub mod stress;
