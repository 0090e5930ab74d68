//! Expressions: the constitutive laws written in model files and the
//! symbolic form of the derived equations.
//!
//! One tree type, [`Expr`], serves three uses:
//! - parsing a law from a model file (`tau_c * tanh(f / 0.01)`), with the
//!   column of a bad token in the error ([`parse`], [`ParseError`]);
//! - printing derived equations as text ([`Display`](fmt::Display)) and LaTeX
//!   ([`Expr::to_latex`]) in the paper's notation, after [`Expr::simplify`];
//!   [`linear_form`] splits a state equation into its `A`/`B` coefficients;
//! - compiling to a flat [`Tape`] ([`TapeBuilder`]) that the simulator
//!   evaluates without walking a tree or looking up a name.
//!
//! ```
//! # use modelgap_bond::expr::{parse, Expr};
//! let law = parse("tau_c * tanh(f / 0.01) + b * f")?;
//! assert_eq!(law.params().into_iter().collect::<Vec<_>>(), ["b", "tau_c"]);
//! let value = law.eval(&|leaf: &Expr| match leaf {
//!     Expr::Param(name) if name == "tau_c" => Some(0.2),
//!     Expr::Param(_) => Some(0.01),
//!     Expr::Local(_) => Some(1.0),
//!     _ => None,
//! });
//! assert!((value.unwrap_or(f64::NAN) - 0.21).abs() < 1e-12);
//! # Ok::<(), modelgap_bond::expr::ParseError>(())
//! ```
//!
//! Submodules: `parse` (text → tree), `print` (tree → text, LaTeX),
//! `algebra` ([`Expr::simplify`], [`linear_form`]), `tape` (tree → [`Tape`]).

mod algebra;
mod parse;
mod print;
mod tape;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::ops;

pub use algebra::linear_form;
pub use parse::{ParseError, parse};
pub use print::var_latex;
pub use tape::{Leaf, Tape, TapeBuilder};

/// A bond-graph variable, named as in the paper's equations (`e3`, `f8`, `p3`, `q5`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Var {
    /// Effort on a bond, by bond number.
    E(u32),
    /// Flow on a bond, by bond number.
    F(u32),
    /// Generalized momentum of the I element on a bond (integral of its effort).
    P(u32),
    /// Generalized displacement of the C element on a bond (integral of its flow).
    Q(u32),
    /// Time derivative of the momentum on a bond (`ṗ3`), equal to the bond's effort.
    Pdot(u32),
    /// Time derivative of the displacement on a bond (`q̇5`), equal to the bond's flow.
    Qdot(u32),
    /// A measured output given as an expression (`y1 = gain * q5 + offset`),
    /// by output number (1-based, in the model's order).
    Y(u32),
}

impl fmt::Display for Var {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Var::E(n) => write!(f, "e{n}"),
            Var::F(n) => write!(f, "f{n}"),
            Var::P(n) => write!(f, "p{n}"),
            Var::Q(n) => write!(f, "q{n}"),
            Var::Pdot(n) => write!(f, "dp{n}"),
            Var::Qdot(n) => write!(f, "dq{n}"),
            Var::Y(n) => write!(f, "y{n}"),
        }
    }
}

/// An elementary function usable in a law.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Func {
    /// `sin(x)`
    Sin,
    /// `cos(x)`
    Cos,
    /// `tan(x)`
    Tan,
    /// `tanh(x)`
    Tanh,
    /// `exp(x)`
    Exp,
    /// `ln(x)` (also accepted as `log`)
    Ln,
    /// `sqrt(x)`
    Sqrt,
    /// `abs(x)`
    Abs,
    /// `sign(x)`: −1, 0 or 1
    Sign,
    /// `atan(x)`
    Atan,
    /// `min(a, b)`
    Min,
    /// `max(a, b)`
    Max,
    /// `atan2(y, x)`
    Atan2,
    /// `quantise(x, q)`: `x` rounded to the nearest multiple of `q` (a
    /// converter's or a driver's steps); `x` itself when `q ≤ 0`.
    Quantise,
}

impl Func {
    /// Every function, in declaration order.
    pub const ALL: [Func; 14] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Tanh,
        Func::Exp,
        Func::Ln,
        Func::Sqrt,
        Func::Abs,
        Func::Sign,
        Func::Atan,
        Func::Min,
        Func::Max,
        Func::Atan2,
        Func::Quantise,
    ];

    /// The name used in model files and in printed equations (`ln` for [`Func::Ln`]).
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Tanh => "tanh",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Sqrt => "sqrt",
            Func::Abs => "abs",
            Func::Sign => "sign",
            Func::Atan => "atan",
            Func::Min => "min",
            Func::Max => "max",
            Func::Atan2 => "atan2",
            Func::Quantise => "quantise",
        }
    }

    /// Looks a function up by the name written in a law; `log` is an alias of `ln`.
    pub fn from_name(name: &str) -> Option<Func> {
        if name == "log" {
            return Some(Func::Ln);
        }
        Func::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Number of arguments: 2 for `min`, `max`, `atan2` and `quantise`, 1 otherwise.
    pub fn arity(self) -> usize {
        match self {
            Func::Min | Func::Max | Func::Atan2 | Func::Quantise => 2,
            _ => 1,
        }
    }

    /// Applies the function, or `None` when `args.len()` is not its [arity](Func::arity).
    ///
    /// Values outside the domain give NaN (`ln(-1)`, `sqrt(-1)`); `sign(0) = 0`.
    /// The tree evaluator and the [`Tape`] share this code, so they agree bit for bit.
    pub fn apply(self, args: &[f64]) -> Option<f64> {
        match *args {
            [x] if self.arity() == 1 => Some(self.apply1(x)),
            [a, b] if self.arity() == 2 => Some(self.apply2(a, b)),
            _ => None,
        }
    }

    /// A unary function; NaN for a binary one (never reached through [`Func::apply`]).
    #[inline]
    pub(crate) fn apply1(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Tanh => x.tanh(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Sqrt => x.sqrt(),
            Func::Abs => x.abs(),
            Func::Sign => sign(x),
            Func::Atan => x.atan(),
            Func::Min | Func::Max | Func::Atan2 | Func::Quantise => f64::NAN,
        }
    }

    /// A binary function; NaN for a unary one (never reached through [`Func::apply`]).
    #[inline]
    pub(crate) fn apply2(self, a: f64, b: f64) -> f64 {
        match self {
            Func::Min => a.min(b),
            Func::Max => a.max(b),
            Func::Atan2 => a.atan2(b),
            Func::Quantise => quantise(a, b),
            _ => f64::NAN,
        }
    }
}

impl fmt::Display for Func {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `sign(x)`: −1, 0 or 1, and NaN for NaN (unlike `f64::signum`, `sign(0) = 0`).
#[inline]
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        x * 0.0 // 0 for ±0 (keeping the sign of zero), NaN for NaN
    }
}

/// `x` rounded to the nearest multiple of `q` (halves away from zero); `x`
/// when `q ≤ 0` (no steps), NaN when either is NaN.
#[inline]
fn quantise(x: f64, q: f64) -> f64 {
    if q > 0.0 {
        q * (x / q).round()
    } else if q.is_nan() {
        q
    } else {
        x
    }
}

/// Largest integer exponent evaluated by repeated multiplication (`powi`)
/// rather than `powf`; larger ones lose accuracy that way.
const POWI_MAX: f64 = 16.0;

/// `a ^ b` as both evaluators compute it: `powi` for small integer exponents
/// (fast, and exact for squares), `powf` otherwise.
#[inline]
fn pow(a: f64, b: f64) -> f64 {
    match small_int(b) {
        Some(n) => a.powi(n),
        None => a.powf(b),
    }
}

/// `b` as an `i32` if it is an integer no larger than [`POWI_MAX`] in magnitude.
#[inline]
fn small_int(b: f64) -> Option<i32> {
    (b.fract() == 0.0 && b.abs() <= POWI_MAX).then_some(b as i32)
}

/// An expression tree over numbers, named parameters, named input signals,
/// bond-graph variables and time.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A number.
    Num(f64),
    /// A named model parameter (`R`, `tau_c`).
    Param(String),
    /// A named input signal (`V`, `duty`).
    Input(String),
    /// A bond-graph variable.
    Var(Var),
    /// A bond-graph variable named by element, before it is bound to a bond:
    /// the law's own (`e`, `f`, `p`, `q`) or another element's, a signal
    /// (`Tank1.q`, see [`Expr::signal`] and [`split_signal`]).
    Local(String),
    /// Simulation time `t` (s).
    Time,
    /// `-a`
    Neg(Box<Expr>),
    /// `a + b + …`
    Add(Vec<Expr>),
    /// `a * b * …`
    Mul(Vec<Expr>),
    /// `a / b`
    Div(Box<Expr>, Box<Expr>),
    /// `a ^ b`
    Pow(Box<Expr>, Box<Expr>),
    /// `f(a, …)`
    Call(Func, Vec<Expr>),
}

/// A signal's element and variable (`"Tank1.q"` → `("Tank1", "q")`); `None`
/// for a law's own variable (`"q"`).
pub fn split_signal(local: &str) -> Option<(&str, &str)> {
    local.rsplit_once('.')
}

/// Values that a [`Tape`] reads by slot: everything a law may mention once
/// the names are resolved.
pub type SlotMap = BTreeMap<Var, usize>;

impl Expr {
    /// A named parameter (`Expr::Param`).
    pub fn param(name: impl Into<String>) -> Expr {
        Expr::Param(name.into())
    }

    /// A named input signal (`Expr::Input`).
    pub fn input(name: impl Into<String>) -> Expr {
        Expr::Input(name.into())
    }

    /// The variable `var` (`e`, `f`, `p` or `q`) of the element called
    /// `element`, read as a signal by another element's law or an output.
    pub fn signal(element: &str, var: &str) -> Expr {
        Expr::Local(format!("{element}.{var}"))
    }

    /// The signals (other elements' variables) mentioned, as
    /// `(element, variable)`, sorted.
    pub fn signals(&self) -> BTreeSet<(String, String)> {
        self.locals()
            .iter()
            .filter_map(|n| split_signal(n).map(|(e, v)| (e.to_string(), v.to_string())))
            .collect()
    }

    /// True for leaves: numbers, names, variables and time.
    pub fn is_leaf(&self) -> bool {
        matches!(
            self,
            Expr::Num(_)
                | Expr::Param(_)
                | Expr::Input(_)
                | Expr::Var(_)
                | Expr::Local(_)
                | Expr::Time
        )
    }

    /// Calls `f` on each direct child, left to right (nothing for a leaf).
    fn for_each_child<'a>(&'a self, mut f: impl FnMut(&'a Expr)) {
        match self {
            Expr::Neg(a) => f(a),
            Expr::Add(xs) | Expr::Mul(xs) | Expr::Call(_, xs) => xs.iter().for_each(f),
            Expr::Div(a, b) | Expr::Pow(a, b) => {
                f(a);
                f(b);
            }
            Expr::Num(_)
            | Expr::Param(_)
            | Expr::Input(_)
            | Expr::Var(_)
            | Expr::Local(_)
            | Expr::Time => {}
        }
    }

    /// Calls `f` on every node, parents before children, left to right.
    pub fn walk(&self, f: &mut impl FnMut(&Expr)) {
        f(self);
        self.for_each_child(|c| c.walk(f));
    }

    /// True if `sub` occurs in the tree (compared with `==`), the root included.
    pub fn contains(&self, sub: &Expr) -> bool {
        let mut found = self == sub;
        if !found {
            self.for_each_child(|c| found = found || c.contains(sub));
        }
        found
    }

    /// Names of the parameters mentioned, sorted.
    pub fn params(&self) -> BTreeSet<String> {
        self.names(|e| match e {
            Expr::Param(n) => Some(n),
            _ => None,
        })
    }

    /// Names of the input signals mentioned, sorted.
    pub fn inputs(&self) -> BTreeSet<String> {
        self.names(|e| match e {
            Expr::Input(n) => Some(n),
            _ => None,
        })
    }

    /// Names local to the law (`e`, `f`, `p`, `q`) that are mentioned, sorted.
    pub fn locals(&self) -> BTreeSet<String> {
        self.names(|e| match e {
            Expr::Local(n) => Some(n),
            _ => None,
        })
    }

    fn names(&self, pick: impl Fn(&Expr) -> Option<&String>) -> BTreeSet<String> {
        let mut out = BTreeSet::new();
        self.walk(&mut |e| {
            if let Some(n) = pick(e) {
                out.insert(n.clone());
            }
        });
        out
    }

    /// Bond-graph variables mentioned, sorted.
    pub fn vars(&self) -> BTreeSet<Var> {
        let mut out = BTreeSet::new();
        self.walk(&mut |e| {
            if let Expr::Var(v) = e {
                out.insert(*v);
            }
        });
        out
    }

    /// True if the expression mentions time `t` (an explicitly time-varying law).
    pub fn depends_on_time(&self) -> bool {
        self.contains(&Expr::Time)
    }

    /// Rebuilds the tree, replacing subtrees top-down.
    ///
    /// `f` sees each node before its children: `Some(r)` puts `r` in place of
    /// the whole subtree (and `r` is not visited again), `None` keeps the node
    /// and recurses into its children. Leaves for which `f` returns `None` are
    /// cloned. The result is not simplified.
    pub fn map(&self, f: &mut impl FnMut(&Expr) -> Option<Expr>) -> Expr {
        if let Some(r) = f(self) {
            return r;
        }
        match self {
            Expr::Neg(a) => Expr::Neg(Box::new(a.map(f))),
            Expr::Add(xs) => Expr::Add(xs.iter().map(|x| x.map(f)).collect()),
            Expr::Mul(xs) => Expr::Mul(xs.iter().map(|x| x.map(f)).collect()),
            Expr::Div(a, b) => Expr::Div(Box::new(a.map(f)), Box::new(b.map(f))),
            Expr::Pow(a, b) => Expr::Pow(Box::new(a.map(f)), Box::new(b.map(f))),
            Expr::Call(func, xs) => Expr::Call(*func, xs.iter().map(|x| x.map(f)).collect()),
            leaf => leaf.clone(),
        }
    }

    /// Replaces each bond-graph variable `v` for which `f(v)` is `Some`.
    pub fn substitute_vars(&self, f: impl Fn(Var) -> Option<Expr>) -> Expr {
        self.map(&mut |e| match e {
            Expr::Var(v) => f(*v),
            _ => None,
        })
    }

    /// Evaluates the tree, asking `env` for the value of every leaf other than a number.
    ///
    /// `None` if `env` knows no value for a leaf, or a call has the wrong
    /// number of arguments. The slow path, for tests and one-off evaluation;
    /// the simulator compiles a [`Tape`]. Sums and products are evaluated left
    /// to right; `x^n` for a small integer `n` uses `powi`, as the tape does.
    pub fn eval(&self, env: &impl Fn(&Expr) -> Option<f64>) -> Option<f64> {
        Some(match self {
            Expr::Num(v) => *v,
            Expr::Param(_) | Expr::Input(_) | Expr::Var(_) | Expr::Local(_) | Expr::Time => {
                env(self)?
            }
            Expr::Neg(a) => -a.eval(env)?,
            Expr::Add(xs) => {
                let mut it = xs.iter();
                let mut acc = match it.next() {
                    Some(x) => x.eval(env)?,
                    None => 0.0,
                };
                for x in it {
                    acc += x.eval(env)?;
                }
                acc
            }
            Expr::Mul(xs) => {
                let mut it = xs.iter();
                let mut acc = match it.next() {
                    Some(x) => x.eval(env)?,
                    None => 1.0,
                };
                for x in it {
                    acc *= x.eval(env)?;
                }
                acc
            }
            Expr::Div(a, b) => a.eval(env)? / b.eval(env)?,
            Expr::Pow(a, b) => pow(a.eval(env)?, b.eval(env)?),
            Expr::Call(f, xs) => match xs.as_slice() {
                [x] if f.arity() == 1 => f.apply1(x.eval(env)?),
                [a, b] if f.arity() == 2 => f.apply2(a.eval(env)?, b.eval(env)?),
                _ => return None,
            },
        })
    }
}

impl From<f64> for Expr {
    fn from(v: f64) -> Expr {
        Expr::Num(v)
    }
}

impl From<Var> for Expr {
    fn from(v: Var) -> Expr {
        Expr::Var(v)
    }
}

/// `a + b`, appending to `a` when it already is a sum (no other simplification).
impl ops::Add for Expr {
    type Output = Expr;
    fn add(self, rhs: Expr) -> Expr {
        match self {
            Expr::Add(mut xs) => {
                xs.push(rhs);
                Expr::Add(xs)
            }
            lhs => Expr::Add(vec![lhs, rhs]),
        }
    }
}

/// `a - b` as the sum `a + (-b)`, appending to `a` when it already is a sum.
impl ops::Sub for Expr {
    type Output = Expr;
    fn sub(self, rhs: Expr) -> Expr {
        let term = Expr::Neg(Box::new(rhs));
        match self {
            Expr::Add(mut xs) => {
                xs.push(term);
                Expr::Add(xs)
            }
            lhs => Expr::Add(vec![lhs, term]),
        }
    }
}

/// `a * b`, appending to `a` when it already is a product.
impl ops::Mul for Expr {
    type Output = Expr;
    fn mul(self, rhs: Expr) -> Expr {
        match self {
            Expr::Mul(mut xs) => {
                xs.push(rhs);
                Expr::Mul(xs)
            }
            lhs => Expr::Mul(vec![lhs, rhs]),
        }
    }
}

/// `a / b`.
impl ops::Div for Expr {
    type Output = Expr;
    fn div(self, rhs: Expr) -> Expr {
        Expr::Div(Box::new(self), Box::new(rhs))
    }
}

/// `-a`.
impl ops::Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        Expr::Neg(Box::new(self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collects_names_by_kind() {
        let e = parse("tau_c * tanh(f / 0.01) + b * f + V0 * sin(2 * pi * 50 * t)").unwrap();
        assert_eq!(
            e.params(),
            ["V0", "b", "tau_c"].map(String::from).into_iter().collect()
        );
        assert_eq!(e.locals(), ["f"].map(String::from).into_iter().collect());
        assert!(e.inputs().is_empty());
        assert!(e.depends_on_time());
        assert!(!parse("R * f").unwrap().depends_on_time());
    }

    #[test]
    fn substitute_vars_binds_locals_and_vars() {
        let law = parse("p / L").unwrap();
        let bound = law.map(&mut |e| match e {
            Expr::Local(n) if n == "p" => Some(Expr::Var(Var::P(3))),
            _ => None,
        });
        assert_eq!(bound.vars(), [Var::P(3)].into_iter().collect());
        let back = bound.substitute_vars(|v| (v == Var::P(3)).then(|| Expr::input("u")));
        assert_eq!(back.inputs(), ["u"].map(String::from).into_iter().collect());
        assert!(back.vars().is_empty());
    }

    #[test]
    fn map_is_top_down_and_does_not_revisit_replacements() {
        let e = parse("sin(R) + R").unwrap();
        let mut seen = 0;
        let out = e.map(&mut |e| match e {
            Expr::Param(_) => {
                seen += 1;
                Some(Expr::Param("R".into())) // would loop if revisited
            }
            Expr::Call(..) => Some(Expr::Num(0.0)),
            _ => None,
        });
        assert_eq!(seen, 1);
        assert_eq!(out, Expr::Add(vec![Expr::Num(0.0), Expr::param("R")]));
    }

    #[test]
    fn eval_reports_missing_leaves_and_bad_arity() {
        let env = |e: &Expr| match e {
            Expr::Param(n) if n == "R" => Some(2.0),
            _ => None,
        };
        assert_eq!(parse("R * 3").unwrap().eval(&env), Some(6.0));
        assert_eq!(parse("R * x").unwrap().eval(&env), None);
        assert_eq!(Expr::Call(Func::Sin, vec![]).eval(&env), None);
    }

    #[test]
    fn sign_of_zero_is_zero() {
        assert_eq!(Func::Sign.apply(&[0.0]), Some(0.0));
        assert_eq!(Func::Sign.apply(&[-3.0]), Some(-1.0));
        assert_eq!(Func::Sign.apply(&[2.0]), Some(1.0));
        assert!(Func::Sign.apply(&[f64::NAN]).is_some_and(f64::is_nan));
        assert_eq!(Func::Sign.apply(&[1.0, 2.0]), None);
    }

    #[test]
    fn quantise_rounds_to_its_steps_and_passes_all_without_them() {
        let q = |x: f64, step: f64| Func::Quantise.apply(&[x, step]).unwrap();
        assert_eq!(q(0.74, 0.5), 0.5);
        assert_eq!(q(-0.76, 0.5), -1.0);
        assert_eq!(q(1.25, 0.5), 1.5); // a half away from zero
        assert_eq!(q(0.74, 0.0), 0.74);
        assert!(q(f64::NAN, 0.5).is_nan() && q(1.0, f64::NAN).is_nan());
        assert_eq!(
            parse("quantise(V, 0.5)").unwrap().to_string(),
            "quantise(V, 0.5)"
        );
        // One argument, or three: a typed error that names the function.
        for bad in ["quantise(V)", "quantise(V, 0.5, 1)"] {
            let e = parse(bad).unwrap_err().to_string();
            assert!(e.contains("quantise"), "{bad}: {e}");
        }
    }

    #[test]
    fn func_names_round_trip() {
        for f in Func::ALL {
            assert_eq!(Func::from_name(f.name()), Some(f));
        }
        assert_eq!(Func::from_name("log"), Some(Func::Ln));
        assert_eq!(Func::from_name("foo"), None);
    }

    #[test]
    fn operators_build_flat_sums_and_products() {
        let e = Expr::Var(Var::E(1)) - Expr::Var(Var::E(2)) - Expr::Var(Var::E(4));
        assert_eq!(e.to_string(), "e1 - e2 - e4");
        let m = Expr::param("R") * Expr::Var(Var::F(2));
        assert_eq!(m.to_string(), "R*f2");
    }
}
