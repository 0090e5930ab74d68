//! The `modelgap` command-line tool.
fn main() {}
