//! `modelgap demo`: the Table 7 diagnosis of the DC-motor paper (being wired).

/// Runs the main demonstration.
///
/// # Errors
///
/// None yet: the demonstration is being wired.
pub fn run_demo() -> anyhow::Result<()> {
    super::print("the Table 7 demo is being wired\n")
}
