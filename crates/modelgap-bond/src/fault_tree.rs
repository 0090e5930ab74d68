//! Fault trees by back-propagation through the causal graph.
//!
//! Start at a measured variable with its observed qualitative value, and
//! walk consequent → antecedent: an edge of sign σ asks its antecedent for
//! the value `q·σ`; a parameter on the consequent's equation whose effect
//! has sign σ becomes a fault candidate with deviation `q·σ`. A path stops
//! where it would give a variable the opposite of a value it already has on
//! that path (the paper's "conflicting assignment"); a (variable, value) pair
//! already expanded elsewhere in the tree is not expanded again.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use crate::causal_graph::CausalGraph;
use crate::error::{BondError, Result};
use crate::expr::Var;
use crate::qual::Qual;

/// A fault hypothesis: a parameter and the direction of its deviation.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Hypothesis {
    /// The parameter.
    pub param: String,
    /// Its deviation from nominal.
    pub deviation: Qual,
}

impl std::fmt::Display for Hypothesis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}{}", self.param, self.deviation)
    }
}

/// One node of a fault tree: a variable with the value it must take.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeNode {
    /// The variable.
    pub var: Var,
    /// The value it must take.
    pub qual: Qual,
    /// The node it explains (`None` for the root).
    pub parent: Option<usize>,
    /// Parameters that explain this node directly.
    pub params: Vec<Hypothesis>,
    /// True when the path stopped here at a conflicting assignment.
    pub conflict: bool,
    /// True when the node was expanded elsewhere in the tree.
    pub repeated: bool,
}

/// The fault tree of one measured variable and its qualitative value.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultTree {
    /// The output's name.
    pub output: String,
    /// Its qualitative value.
    pub qual: Qual,
    /// Nodes, root first.
    pub nodes: Vec<TreeNode>,
}

impl FaultTree {
    /// Every fault candidate the tree reaches.
    pub fn candidates(&self) -> BTreeSet<Hypothesis> {
        self.nodes
            .iter()
            .flat_map(|n| n.params.iter().cloned())
            .collect()
    }

    /// The tree as indented text (`f3- <- p3- <- dp3- …`, parameters in brackets).
    pub fn to_text(&self) -> String {
        let mut children: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some(p) = n.parent {
                children.entry(p).or_default().push(i);
            }
        }
        let mut s = String::new();
        let _ = writeln!(s, "fault tree of {} {}:", self.output, self.qual);
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            let params = if n.params.is_empty() {
                String::new()
            } else {
                format!(
                    "  [{}]",
                    n.params
                        .iter()
                        .map(|h| h.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            };
            let mark = if n.conflict {
                "  (conflict: stop)"
            } else if n.repeated {
                "  (see above)"
            } else {
                ""
            };
            let _ = writeln!(s, "{}{}{}{params}{mark}", "  ".repeat(depth), n.var, n.qual);
            if let Some(c) = children.get(&i) {
                for &ci in c.iter().rev() {
                    stack.push((ci, depth + 1));
                }
            }
        }
        s
    }
}

/// Builds the fault tree of `output` observed with value `qual`.
///
/// # Errors
/// [`BondError::BadOutput`] if the graph has no such measured output.
pub fn fault_tree(cg: &CausalGraph, output: &str, qual: Qual) -> Result<FaultTree> {
    let var = cg
        .measured
        .iter()
        .find(|(n, _)| n == output)
        .map(|(_, v)| *v)
        .ok_or_else(|| BondError::BadOutput {
            output: output.to_string(),
            detail: format!(
                "is not a measured output (outputs: {})",
                cg.measured
                    .iter()
                    .map(|(n, _)| n.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })?;
    let mut tree = FaultTree {
        output: output.to_string(),
        qual,
        nodes: Vec::new(),
    };
    if qual == Qual::Zero {
        return Ok(tree);
    }
    let mut expanded: BTreeSet<(Var, Qual)> = BTreeSet::new();
    // Depth-first with an explicit stack: (var, qual, parent, path assignments).
    // (variable, value, parent node, the assignments along the path to it)
    type Pending = (Var, Qual, Option<usize>, BTreeMap<Var, Qual>);
    let mut stack: Vec<Pending> = vec![(var, qual, None, BTreeMap::new())];
    while let Some((v, q, parent, mut path)) = stack.pop() {
        let conflict = path.get(&v).is_some_and(|&p| p != q);
        let repeated = !conflict && !expanded.insert((v, q));
        let params: Vec<Hypothesis> = if conflict {
            Vec::new()
        } else {
            cg.param_effects
                .iter()
                .filter(|e| e.on == v && e.sign != Qual::Zero)
                .map(|e| Hypothesis {
                    param: e.param.clone(),
                    deviation: q * e.sign,
                })
                .collect()
        };
        let idx = tree.nodes.len();
        tree.nodes.push(TreeNode {
            var: v,
            qual: q,
            parent,
            params,
            conflict,
            repeated,
        });
        if conflict || repeated {
            continue;
        }
        path.insert(v, q);
        let ants: Vec<(Var, Qual)> = cg
            .antecedents(v)
            .filter(|e| e.sign != Qual::Zero)
            .map(|e| (e.from, q * e.sign))
            .collect();
        for (a, qa) in ants.into_iter().rev() {
            stack.push((a, qa, Some(idx), path.clone()));
        }
    }
    Ok(tree)
}

/// The first fault-hypothesis set: the (parameter, deviation) pairs found
/// in every tree. Empty input gives an empty set.
pub fn first_hypothesis_set(trees: &[FaultTree]) -> BTreeSet<Hypothesis> {
    let mut it = trees.iter().filter(|t| t.qual != Qual::Zero);
    let Some(first) = it.next() else {
        return BTreeSet::new();
    };
    let mut set = first.candidates();
    for t in it {
        let c = t.candidates();
        set.retain(|h| c.contains(h));
    }
    set
}
