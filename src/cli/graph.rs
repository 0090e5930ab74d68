//! `modelgap bond graph`: the causal graph as Graphviz DOT, or its antecedents/consequents
//! table.

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::causal_graph::CausalGraph;
use modelgap::bond::{Equations, assign_causality};

use super::model::{ModelArgs, load};

/// Arguments of `modelgap bond graph`.
#[derive(Debug, Args)]
pub struct GraphArgs {
    #[command(flatten)]
    model: ModelArgs,

    /// Print the antecedents/consequents table instead of DOT
    #[arg(long)]
    table: bool,
}

/// Prints the causal graph (signs taken at the steady state under the default inputs).
///
/// # Errors
///
/// Model errors, causal conflicts, derivative causality and algebraic loops.
pub fn run(args: &GraphArgs) -> anyhow::Result<()> {
    let g = load(&args.model)?;
    let c =
        assign_causality(&g).with_context(|| format!("assigning causality to model {}", g.name))?;
    let eqs = Equations::derive(&g, &c)
        .with_context(|| format!("deriving the equations of model {}", g.name))?;
    let cg = CausalGraph::from_graph(&g, &eqs)
        .with_context(|| format!("building the causal graph of model {}", g.name))?;
    if args.table {
        super::print(&cg.table())
    } else {
        super::print(&cg.to_dot())
    }
}
