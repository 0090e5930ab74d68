//! Temporal signatures (Mosterman & Biswas): how an abrupt parameter fault
//! shows in each measurement at its onset — the sign of the jump in the
//! magnitude, the first and the second derivative.
//!
//! Prediction walks the causal graph forward from the faulty parameter:
//! crossing an integrating edge (a storage element) moves the effect one
//! derivative order up. Effects that only arrive through the integration of
//! a fast storage element (its local time constant below a threshold) are
//! over before a detector can see them and are discarded (the paper's
//! Table 6). Observation reads the same three signs off a residual right
//! after detection.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use crate::causal_graph::CausalGraph;
use crate::expr::Var;
use crate::fault_tree::Hypothesis;
use crate::qual::Qual;

/// One component of a predicted signature.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Sym {
    /// Decrease.
    Minus,
    /// No change at this order.
    Zero,
    /// Increase.
    Plus,
    /// Opposite effects meet: the sign cannot be told qualitatively.
    Ambiguous,
    /// Only through fast dynamics: not observable, not used for matching.
    Discarded,
}

impl Sym {
    fn of(q: Qual) -> Sym {
        match q {
            Qual::Minus => Sym::Minus,
            Qual::Zero => Sym::Zero,
            Qual::Plus => Sym::Plus,
        }
    }

    fn add(self, other: Sym) -> Sym {
        match (self, other) {
            (Sym::Zero, x) | (x, Sym::Zero) => x,
            (a, b) if a == b => a,
            _ => Sym::Ambiguous,
        }
    }

    fn times(self, q: Qual) -> Sym {
        match (self, q) {
            (_, Qual::Zero) => Sym::Zero,
            (s, Qual::Plus) => s,
            (Sym::Plus, Qual::Minus) => Sym::Minus,
            (Sym::Minus, Qual::Minus) => Sym::Plus,
            (s, Qual::Minus) => s,
        }
    }

    /// The qualitative value, if the symbol is a definite sign.
    pub fn qual(self) -> Option<Qual> {
        match self {
            Sym::Minus => Some(Qual::Minus),
            Sym::Zero => Some(Qual::Zero),
            Sym::Plus => Some(Qual::Plus),
            _ => None,
        }
    }
}

impl fmt::Display for Sym {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Sym::Minus => "-",
            Sym::Zero => "0",
            Sym::Plus => "+",
            Sym::Ambiguous => "?",
            Sym::Discarded => "*",
        })
    }
}

/// Number of derivative orders propagated: magnitude and five derivatives
/// (an effect behind three storage elements first shows in the third
/// derivative). Printed signatures show the first three.
pub const ORDERS: usize = 6;

/// The predicted signature of one fault on one measurement.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Signature {
    /// The measurement.
    pub output: String,
    /// Magnitude, first-derivative and second-derivative symbols.
    pub orders: [Sym; ORDERS],
    /// When the first effect of the full propagation is discarded (it runs
    /// through a fast storage element), its order and sign: sampled slower
    /// than that element settles, it shows as a jump of this sign.
    pub fast: Option<(usize, Sym)>,
}

impl Signature {
    /// The first order with a definite or ambiguous effect, with its symbol
    /// (discarded and zero orders skipped).
    pub fn first_effect(&self) -> Option<(usize, Sym)> {
        self.orders
            .iter()
            .copied()
            .enumerate()
            .find(|(_, s)| !matches!(s, Sym::Zero | Sym::Discarded))
    }
}

impl fmt::Display for Signature {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: ({}, {}, {})",
            self.output, self.orders[0], self.orders[1], self.orders[2]
        )?;
        match self.first_effect() {
            Some((k, s)) if k > 2 => write!(f, " first {s} at order {k}"),
            _ => Ok(()),
        }
    }
}

/// Predicts the signature of `fault` on every measured output.
///
/// `fast` lists the states (`p3`) whose local time constant is too small for
/// their integrations to be observed; effects that need them are discarded,
/// and a first effect that a later effect through them opposes becomes
/// ambiguous (it is over before the next sample).
pub fn predict(cg: &CausalGraph, fault: &Hypothesis, fast: &BTreeSet<Var>) -> Vec<Signature> {
    let full = propagate(cg, fault, &BTreeSet::new());
    let slow = if fast.is_empty() {
        full.clone()
    } else {
        propagate(cg, fault, fast)
    };
    cg.measured
        .iter()
        .map(|(name, v)| {
            let mut orders = [Sym::Zero; ORDERS];
            let mut fast_effect = None;
            for (j, o) in orders.iter_mut().enumerate() {
                let f = full[j].get(v).copied().unwrap_or(Sym::Zero);
                let s = slow[j].get(v).copied().unwrap_or(Sym::Zero);
                *o = if f != Sym::Zero && s == Sym::Zero {
                    Sym::Discarded
                } else {
                    s
                };
                if fast_effect.is_none() && f != Sym::Zero {
                    fast_effect = Some((j, f));
                }
            }
            let fast = fast_effect.filter(|&(j, _)| orders[j] == Sym::Discarded);
            // A slow first effect that a later effect through a fast element
            // opposes is over within that element's time constant: sampled
            // slower, its sign cannot be relied on.
            let first = orders
                .iter()
                .position(|o| !matches!(o, Sym::Zero | Sym::Discarded));
            if let Some(k) = first {
                let s = orders[k];
                let opposed = (k + 1..ORDERS).any(|j| {
                    let f = full[j].get(v).copied().unwrap_or(Sym::Zero);
                    let sl = slow[j].get(v).copied().unwrap_or(Sym::Zero);
                    f != sl && f != s && f != Sym::Zero
                });
                if opposed {
                    orders[k] = Sym::Ambiguous;
                }
            }
            Signature {
                output: name.clone(),
                orders,
                fast,
            }
        })
        .collect()
}

/// Per-order forward propagation; integrations of states in `cut` are blocked.
fn propagate(cg: &CausalGraph, fault: &Hypothesis, cut: &BTreeSet<Var>) -> Vec<BTreeMap<Var, Sym>> {
    let order = algebraic_order(cg);
    let mut out: Vec<BTreeMap<Var, Sym>> = Vec::with_capacity(ORDERS);
    for j in 0..ORDERS {
        let mut val: BTreeMap<Var, Sym> = BTreeMap::new();
        if j == 0 {
            for e in cg.param_effects.iter().filter(|e| e.param == fault.param) {
                let s = Sym::of(e.sign * fault.deviation);
                let cur = val.get(&e.on).copied().unwrap_or(Sym::Zero);
                val.insert(e.on, cur.add(s));
            }
        }
        for &v in &order {
            let mut acc = val.get(&v).copied().unwrap_or(Sym::Zero);
            for e in cg.antecedents(v) {
                let src = if e.integrating {
                    if j == 0 || cut.contains(&e.to) {
                        Sym::Zero
                    } else {
                        out[j - 1].get(&e.from).copied().unwrap_or(Sym::Zero)
                    }
                } else {
                    val.get(&e.from).copied().unwrap_or(Sym::Zero)
                };
                acc = acc.add(src.times(e.sign));
            }
            val.insert(v, acc);
        }
        out.push(val);
    }
    out
}

/// Variables in an order where every algebraic antecedent comes first
/// (states first: they have only integrating antecedents).
fn algebraic_order(cg: &CausalGraph) -> Vec<Var> {
    let mut done: BTreeSet<Var> = BTreeSet::new();
    let mut order = Vec::with_capacity(cg.nodes.len());
    loop {
        let mut progressed = false;
        for &v in &cg.nodes {
            if done.contains(&v) {
                continue;
            }
            if cg
                .antecedents(v)
                .all(|e| e.integrating || done.contains(&e.from))
            {
                done.insert(v);
                order.push(v);
                progressed = true;
            }
        }
        if !progressed {
            break;
        }
    }
    // Anything left sits on an algebraic loop (the equations' sort refuses
    // those, so this is defensive): append in node order.
    for &v in &cg.nodes {
        if !done.contains(&v) {
            order.push(v);
        }
    }
    order
}

/// What a residual shows right after the fault's onset.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObservedSignature {
    /// The measurement.
    pub output: String,
    /// Sign of the first change after onset (0 while the residual is quiet).
    pub magnitude: Qual,
    /// True when the first sample after onset already holds most of the
    /// change (a discontinuity: a magnitude-order effect).
    pub jump: bool,
    /// Sign of the residual's slope at onset.
    pub slope: Qual,
    /// Estimated order of the first change (0 = jump), from the growth of
    /// the residual over the first samples after onset.
    pub order: Option<usize>,
}

impl fmt::Display for ObservedSignature {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {}{} slope {}",
            self.output,
            self.magnitude,
            if self.jump { " (jump)" } else { "" },
            self.slope
        )?;
        match self.order {
            Some(k) => write!(f, " order {k}"),
            None => Ok(()),
        }
    }
}

/// True when a predicted signature agrees with an observed one.
///
/// - A measurement that deviates must do so with the sign of the predicted
///   first effect, and jump exactly when that effect is of order 0 (the
///   Mosterman–Biswas discriminator between magnitude and derivative
///   effects); an estimated order may be one off (fast dynamics blur it).
/// - A measurement still quiet matches anything (a slow effect, or a jump
///   smaller than the noise).
/// - An effect through a fast storage element (discarded) matches a change
///   of its sign, jump or not: at the sampling it shows as either.
/// - Ambiguous components match either sign; an output with no predicted
///   effect must show no deviation.
pub fn matches(predicted: &Signature, observed: &ObservedSignature) -> bool {
    if observed.magnitude == Qual::Zero {
        // Still quiet: consistent with a slow effect, and with a jump too
        // small to see.
        return true;
    }
    let same_sign = |s: Sym| s.qual().is_none_or(|q| q == observed.magnitude);
    // A fast first effect shows as a jump of its sign at this sampling, or,
    // when the sampling resolves it, as a derivative change of that sign.
    if let Some((_, s)) = predicted.fast
        && same_sign(s)
    {
        return true;
    }
    let Some((k, s)) = predicted.first_effect() else {
        return false;
    };
    if observed.jump != (k == 0) {
        return false;
    }
    // Orders estimated from growth blur under fast dynamics: allow one off,
    // and any order when fast elements shape the prediction.
    let blurred = predicted
        .orders
        .iter()
        .any(|o| matches!(o, Sym::Ambiguous | Sym::Discarded));
    if let Some(ko) = observed.order
        && ko.abs_diff(k) > 1
        && !blurred
    {
        return false;
    }
    same_sign(s)
}
