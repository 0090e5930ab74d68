//! [`Expr`] → [`Tape`]: causal assignments compiled to a flat list of
//! register operations over one `f64` slice, evaluated without allocation.

use std::collections::BTreeSet;
use std::fmt;

use super::{Expr, Func, pow, small_int};

/// What a leaf of an expression stands for on a tape, as decided by the
/// caller's resolver in [`TapeBuilder::assign`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Leaf {
    /// A value fixed at compile time (a parameter); folded into the ops.
    Const(f64),
    /// A caller-owned slot (time, a state, an input, a bond variable) read at
    /// evaluation time; must be below the builder's `n_fixed`.
    Slot(usize),
}

/// One tape instruction: `dst ← f(operands)`. Slots are `u32` to keep ops small
/// (24 bytes); every op reads all its operands before writing `dst`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Const {
        dst: u32,
        k: f64,
    },
    Copy {
        dst: u32,
        a: u32,
    },
    Neg {
        dst: u32,
        a: u32,
    },
    Add {
        dst: u32,
        a: u32,
        b: u32,
    },
    Sub {
        dst: u32,
        a: u32,
        b: u32,
    },
    Mul {
        dst: u32,
        a: u32,
        b: u32,
    },
    Div {
        dst: u32,
        a: u32,
        b: u32,
    },
    /// `a + k`
    AddK {
        dst: u32,
        a: u32,
        k: f64,
    },
    /// `k - a`
    KSub {
        dst: u32,
        k: f64,
        a: u32,
    },
    /// `a * k`
    MulK {
        dst: u32,
        a: u32,
        k: f64,
    },
    /// `a / k`
    DivK {
        dst: u32,
        a: u32,
        k: f64,
    },
    /// `k / a`
    KDiv {
        dst: u32,
        k: f64,
        a: u32,
    },
    Pow {
        dst: u32,
        a: u32,
        b: u32,
    },
    /// `a ^ k` for a constant `k` that is not a small integer
    PowK {
        dst: u32,
        a: u32,
        k: f64,
    },
    /// `a ^ n` by `powi`
    PowI {
        dst: u32,
        a: u32,
        n: i32,
    },
    Call1 {
        dst: u32,
        f: Func,
        a: u32,
    },
    Call2 {
        dst: u32,
        f: Func,
        a: u32,
        b: u32,
    },
}

impl Op {
    /// The highest slot the op reads or writes.
    fn max_slot(&self) -> u32 {
        match *self {
            Op::Const { dst, .. } => dst,
            Op::Copy { dst, a }
            | Op::Neg { dst, a }
            | Op::AddK { dst, a, .. }
            | Op::KSub { dst, a, .. }
            | Op::MulK { dst, a, .. }
            | Op::DivK { dst, a, .. }
            | Op::KDiv { dst, a, .. }
            | Op::PowK { dst, a, .. }
            | Op::PowI { dst, a, .. }
            | Op::Call1 { dst, a, .. } => dst.max(a),
            Op::Add { dst, a, b }
            | Op::Sub { dst, a, b }
            | Op::Mul { dst, a, b }
            | Op::Div { dst, a, b }
            | Op::Pow { dst, a, b }
            | Op::Call2 { dst, a, b, .. } => dst.max(a).max(b),
        }
    }

    fn dst_mut(&mut self) -> &mut u32 {
        match self {
            Op::Const { dst, .. }
            | Op::Copy { dst, .. }
            | Op::Neg { dst, .. }
            | Op::Add { dst, .. }
            | Op::Sub { dst, .. }
            | Op::Mul { dst, .. }
            | Op::Div { dst, .. }
            | Op::AddK { dst, .. }
            | Op::KSub { dst, .. }
            | Op::MulK { dst, .. }
            | Op::DivK { dst, .. }
            | Op::KDiv { dst, .. }
            | Op::Pow { dst, .. }
            | Op::PowK { dst, .. }
            | Op::PowI { dst, .. }
            | Op::Call1 { dst, .. }
            | Op::Call2 { dst, .. } => dst,
        }
    }
}

impl fmt::Display for Op {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Op::Const { dst, k } => write!(f, "s{dst} = {k:?}"),
            Op::Copy { dst, a } => write!(f, "s{dst} = s{a}"),
            Op::Neg { dst, a } => write!(f, "s{dst} = -s{a}"),
            Op::Add { dst, a, b } => write!(f, "s{dst} = s{a} + s{b}"),
            Op::Sub { dst, a, b } => write!(f, "s{dst} = s{a} - s{b}"),
            Op::Mul { dst, a, b } => write!(f, "s{dst} = s{a} * s{b}"),
            Op::Div { dst, a, b } => write!(f, "s{dst} = s{a} / s{b}"),
            Op::AddK { dst, a, k } => write!(f, "s{dst} = s{a} + {k:?}"),
            Op::KSub { dst, k, a } => write!(f, "s{dst} = {k:?} - s{a}"),
            Op::MulK { dst, a, k } => write!(f, "s{dst} = s{a} * {k:?}"),
            Op::DivK { dst, a, k } => write!(f, "s{dst} = s{a} / {k:?}"),
            Op::KDiv { dst, k, a } => write!(f, "s{dst} = {k:?} / s{a}"),
            Op::Pow { dst, a, b } => write!(f, "s{dst} = s{a} ^ s{b}"),
            Op::PowK { dst, a, k } => write!(f, "s{dst} = s{a} ^ {k:?}"),
            Op::PowI { dst, a, n } => write!(f, "s{dst} = s{a} ^ {n}"),
            Op::Call1 { dst, f: func, a } => write!(f, "s{dst} = {func}(s{a})"),
            Op::Call2 { dst, f: func, a, b } => write!(f, "s{dst} = {func}(s{a}, s{b})"),
        }
    }
}

/// A compiled operand: folded to a constant, or held in a slot.
#[derive(Clone, Copy, Debug)]
enum Val {
    K(f64),
    S(u32),
}

/// Compiles an ordered list of assignments `slot ← expression` into a [`Tape`].
///
/// Slots `0..n_fixed` belong to the caller (time, states, inputs, bond
/// variables, outputs); temporaries live above them and are reused across
/// assignments, so [`Tape::n_slots`] is `n_fixed` plus the largest number
/// of temporaries any one assignment needs.
///
/// # Example
///
/// ```
/// # use modelgap_bond::expr::{parse, Expr, Leaf, TapeBuilder};
/// // An R element with Coulomb friction: e = tau_c*tanh(f/0.01) + b*f.
/// let law = parse("tau_c * tanh(f / 0.01) + b * f")?;
/// const F: usize = 0; // slot of the flow, written by the caller
/// const E: usize = 1; // slot of the effort, written by the tape
/// let mut builder = TapeBuilder::new(2);
/// builder.assign(E, &law, &mut |leaf: &Expr| match leaf {
///     Expr::Local(n) if n == "f" => Ok(Leaf::Slot(F)),
///     Expr::Param(n) if n == "tau_c" => Ok(Leaf::Const(0.2)),
///     Expr::Param(n) if n == "b" => Ok(Leaf::Const(0.01)),
///     other => Err(format!("unknown name '{other}'")),
/// })?;
/// let tape = builder.finish();
/// let mut slots = vec![0.0; tape.n_slots()];
/// slots[F] = 1.0;
/// tape.eval(&mut slots);
/// assert!((slots[E] - 0.21).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct TapeBuilder {
    n_fixed: u32,
    ops: Vec<Op>,
    /// Temporaries not in use, lowest first.
    free: BTreeSet<u32>,
    /// One past the highest slot allocated so far (at least `n_fixed`); the
    /// tape's size is taken from the ops, which may use fewer.
    high: u32,
}

impl TapeBuilder {
    /// A builder whose first `n_fixed` slots are owned by the caller;
    /// temporaries go after them.
    ///
    /// # Panics
    ///
    /// If `n_fixed` does not fit the tape's 32-bit slot indices.
    pub fn new(n_fixed: usize) -> Self {
        let n_fixed = u32::try_from(n_fixed)
            .ok()
            .filter(|n| *n < u32::MAX / 2)
            .unwrap_or_else(|| panic!("{n_fixed} fixed slots do not fit a tape"));
        TapeBuilder {
            n_fixed,
            ops: Vec::new(),
            free: BTreeSet::new(),
            high: n_fixed,
        }
    }

    /// Number of caller-owned slots.
    pub fn n_fixed(&self) -> usize {
        self.n_fixed as usize
    }

    /// Emits ops computing `expr` into slot `dst`.
    ///
    /// Every leaf (`Param`, `Input`, `Var`, `Local`, `Time`) is resolved by
    /// `resolve`, once per occurrence. Constant subtrees are folded at compile
    /// time (after resolution, parameters are constants), so `R/L*p3` is a
    /// single multiply; numbers in a sum or product are gathered into one
    /// constant (`2*x*3` → `x*6`), which may round differently from the tree
    /// in the last bits. The assignment may read `dst` and earlier slots;
    /// later assignments see its result.
    ///
    /// # Errors
    ///
    /// The first `Err` returned by `resolve`, as is; the builder is then left
    /// as it was before the call.
    ///
    /// # Panics
    ///
    /// If `dst` or a resolved [`Leaf::Slot`] is not below `n_fixed`, or a
    /// call has the wrong number of arguments (the parser never builds one).
    pub fn assign<E>(
        &mut self,
        dst: usize,
        expr: &Expr,
        resolve: &mut impl FnMut(&Expr) -> Result<Leaf, E>,
    ) -> Result<(), E> {
        let dst = self.fixed_slot(dst);
        let (mark, free, high) = (self.ops.len(), self.free.clone(), self.high);
        let val = match self.compile(expr, resolve) {
            Ok(v) => v,
            Err(e) => {
                self.ops.truncate(mark);
                self.free = free;
                self.high = high;
                return Err(e);
            }
        };
        match val {
            Val::K(k) => self.ops.push(Op::Const { dst, k }),
            Val::S(s) if s == dst => {}
            Val::S(s) => {
                let last_writes_s = self.ops.len() > mark
                    && self.ops.last_mut().is_some_and(|op| *op.dst_mut() == s);
                match self.ops.last_mut() {
                    // Retarget the op that produced the temporary.
                    Some(op) if s >= self.n_fixed && last_writes_s => *op.dst_mut() = dst,
                    _ => self.ops.push(Op::Copy { dst, a: s }),
                }
                self.release(val);
            }
        }
        debug_assert_eq!(
            self.free.len(),
            (self.high - self.n_fixed) as usize,
            "every temporary is free between assignments"
        );
        Ok(())
    }

    /// The finished tape.
    pub fn finish(self) -> Tape {
        let n_slots = (self.ops.iter())
            .map(|op| op.max_slot() as usize + 1)
            .fold(self.n_fixed as usize, usize::max);
        Tape {
            ops: self.ops,
            n_slots,
            n_fixed: self.n_fixed as usize,
        }
    }

    fn fixed_slot(&self, s: usize) -> u32 {
        assert!(
            s < self.n_fixed as usize,
            "slot {s} is not one of the {} caller-owned slots",
            self.n_fixed
        );
        s as u32
    }

    fn alloc(&mut self) -> u32 {
        self.free.pop_first().unwrap_or_else(|| {
            self.high += 1;
            self.high - 1
        })
    }

    fn release(&mut self, v: Val) {
        if let Val::S(s) = v
            && s >= self.n_fixed
        {
            self.free.insert(s);
        }
    }

    /// `v` in a slot, loading a constant into a temporary if needed.
    fn in_slot(&mut self, v: Val) -> u32 {
        match v {
            Val::S(s) => s,
            Val::K(k) => {
                let dst = self.alloc();
                self.ops.push(Op::Const { dst, k });
                dst
            }
        }
    }

    /// Frees the operands, then emits `make(dst)` into a fresh temporary
    /// (often one of the operands: ops read before they write).
    fn emit(&mut self, operands: &[u32], make: impl FnOnce(u32) -> Op) -> Val {
        Val::S(self.emit_slot(operands, make))
    }

    fn emit_slot(&mut self, operands: &[u32], make: impl FnOnce(u32) -> Op) -> u32 {
        for s in operands {
            self.release(Val::S(*s));
        }
        let dst = self.alloc();
        self.ops.push(make(dst));
        dst
    }

    fn compile<E>(
        &mut self,
        e: &Expr,
        resolve: &mut impl FnMut(&Expr) -> Result<Leaf, E>,
    ) -> Result<Val, E> {
        Ok(match e {
            Expr::Num(v) => Val::K(*v),
            Expr::Param(_) | Expr::Input(_) | Expr::Var(_) | Expr::Local(_) | Expr::Time => {
                match resolve(e)? {
                    Leaf::Const(k) => Val::K(k),
                    Leaf::Slot(s) => Val::S(self.fixed_slot(s)),
                }
            }
            Expr::Neg(a) => match self.compile(a, resolve)? {
                Val::K(k) => Val::K(-k),
                Val::S(a) => self.emit(&[a], |dst| Op::Neg { dst, a }),
            },
            Expr::Add(terms) => self.sum(terms, resolve)?,
            Expr::Mul(factors) => self.product(factors, resolve)?,
            Expr::Div(a, b) => {
                let a = self.compile(a, resolve)?;
                match (a, self.compile(b, resolve)?) {
                    (Val::K(x), Val::K(y)) => Val::K(x / y),
                    (Val::S(a), Val::K(k)) => self.emit(&[a], |dst| Op::DivK { dst, a, k }),
                    (Val::K(k), Val::S(a)) => self.emit(&[a], |dst| Op::KDiv { dst, k, a }),
                    (Val::S(a), Val::S(b)) => self.emit(&[a, b], |dst| Op::Div { dst, a, b }),
                }
            }
            Expr::Pow(a, b) => {
                let a = self.compile(a, resolve)?;
                match (a, self.compile(b, resolve)?) {
                    (Val::K(x), Val::K(y)) => Val::K(pow(x, y)),
                    (Val::S(a), Val::K(k)) => match small_int(k) {
                        Some(n) => self.emit(&[a], |dst| Op::PowI { dst, a, n }),
                        None => self.emit(&[a], |dst| Op::PowK { dst, a, k }),
                    },
                    (a, b) => {
                        let a = self.in_slot(a);
                        let b = self.in_slot(b);
                        self.emit(&[a, b], |dst| Op::Pow { dst, a, b })
                    }
                }
            }
            Expr::Call(f, args) => {
                assert_eq!(
                    args.len(),
                    f.arity(),
                    "{f} takes {} argument(s) but the tree gives it {}",
                    f.arity(),
                    args.len()
                );
                let f = *f;
                if let [x] = args.as_slice() {
                    match self.compile(x, resolve)? {
                        Val::K(k) => Val::K(f.apply1(k)),
                        Val::S(a) => self.emit(&[a], |dst| Op::Call1 { dst, f, a }),
                    }
                } else {
                    let a = self.compile(&args[0], resolve)?;
                    match (a, self.compile(&args[1], resolve)?) {
                        (Val::K(x), Val::K(y)) => Val::K(f.apply2(x, y)),
                        (a, b) => {
                            let a = self.in_slot(a);
                            let b = self.in_slot(b);
                            self.emit(&[a, b], |dst| Op::Call2 { dst, f, a, b })
                        }
                    }
                }
            }
        })
    }

    /// A sum: slot terms chained with `+`/`-` left to right, numbers gathered
    /// into one constant added last.
    fn sum<E>(
        &mut self,
        terms: &[Expr],
        resolve: &mut impl FnMut(&Expr) -> Result<Leaf, E>,
    ) -> Result<Val, E> {
        let mut k = 0.0;
        // The running sum so far, and whether it is held negated.
        let mut acc: Option<(u32, bool)> = None;
        for t in terms {
            let (neg, inner) = match t {
                Expr::Neg(x) => (true, &**x),
                t => (false, t),
            };
            match self.compile(inner, resolve)? {
                Val::K(v) => k += if neg { -v } else { v },
                Val::S(s) => {
                    acc = Some(match acc {
                        None => (s, neg),
                        Some((a, a_neg)) => match (a_neg, neg) {
                            (false, false) => (
                                self.emit_slot(&[a, s], |dst| Op::Add { dst, a, b: s }),
                                false,
                            ),
                            (false, true) => (
                                self.emit_slot(&[a, s], |dst| Op::Sub { dst, a, b: s }),
                                false,
                            ),
                            (true, false) => (
                                self.emit_slot(&[a, s], |dst| Op::Sub { dst, a: s, b: a }),
                                false,
                            ),
                            (true, true) => (
                                self.emit_slot(&[a, s], |dst| Op::Add { dst, a, b: s }),
                                true,
                            ),
                        },
                    });
                }
            }
        }
        Ok(match acc {
            None => Val::K(k),
            Some((a, false)) if k == 0.0 => Val::S(a),
            Some((a, false)) => self.emit(&[a], |dst| Op::AddK { dst, a, k }),
            Some((a, true)) if k == 0.0 => self.emit(&[a], |dst| Op::Neg { dst, a }),
            Some((a, true)) => self.emit(&[a], |dst| Op::KSub { dst, k, a }),
        })
    }

    /// A product: slot factors chained with `*` left to right, numbers and
    /// signs gathered into one constant multiplied last.
    fn product<E>(
        &mut self,
        factors: &[Expr],
        resolve: &mut impl FnMut(&Expr) -> Result<Leaf, E>,
    ) -> Result<Val, E> {
        let mut k = 1.0;
        let mut acc: Option<u32> = None;
        for f in factors {
            let mut inner = f;
            while let Expr::Neg(x) = inner {
                k = -k;
                inner = x;
            }
            match self.compile(inner, resolve)? {
                Val::K(v) => k *= v,
                Val::S(s) => {
                    acc = Some(match acc {
                        None => s,
                        Some(a) => self.emit_slot(&[a, s], |dst| Op::Mul { dst, a, b: s }),
                    });
                }
            }
        }
        Ok(match acc {
            None => Val::K(k),
            Some(a) if k == 1.0 => Val::S(a),
            Some(a) if k == -1.0 => self.emit(&[a], |dst| Op::Neg { dst, a }),
            Some(a) => self.emit(&[a], |dst| Op::MulK { dst, a, k }),
        })
    }
}

/// A compiled program: ops over one slice of `f64` slots, evaluated in order.
///
/// Cheap to clone, `Send + Sync`; evaluation allocates nothing.
#[derive(Clone, Debug)]
pub struct Tape {
    ops: Vec<Op>,
    n_slots: usize,
    n_fixed: usize,
}

impl Tape {
    /// Length of the slot slice [`Tape::eval`] needs: the caller's slots plus temporaries.
    pub fn n_slots(&self) -> usize {
        self.n_slots
    }

    /// Number of caller-owned slots (those below the temporaries).
    pub fn n_fixed(&self) -> usize {
        self.n_fixed
    }

    /// Number of operations, a measure of the cost of one [`Tape::eval`].
    pub fn n_ops(&self) -> usize {
        self.ops.len()
    }

    /// Runs the program: reads the caller's slots, writes the assigned ones
    /// (and scratch temporaries above `n_fixed`).
    ///
    /// `slots` must hold at least [`Tape::n_slots`] values (checked in debug
    /// builds; a shorter slice panics on the first out-of-range slot).
    pub fn eval(&self, slots: &mut [f64]) {
        debug_assert!(
            slots.len() >= self.n_slots,
            "tape needs {} slots but got {}",
            self.n_slots,
            slots.len()
        );
        for op in &self.ops {
            match *op {
                Op::Const { dst, k } => slots[dst as usize] = k,
                Op::Copy { dst, a } => slots[dst as usize] = slots[a as usize],
                Op::Neg { dst, a } => slots[dst as usize] = -slots[a as usize],
                Op::Add { dst, a, b } => {
                    slots[dst as usize] = slots[a as usize] + slots[b as usize];
                }
                Op::Sub { dst, a, b } => {
                    slots[dst as usize] = slots[a as usize] - slots[b as usize];
                }
                Op::Mul { dst, a, b } => {
                    slots[dst as usize] = slots[a as usize] * slots[b as usize];
                }
                Op::Div { dst, a, b } => {
                    slots[dst as usize] = slots[a as usize] / slots[b as usize];
                }
                Op::AddK { dst, a, k } => slots[dst as usize] = slots[a as usize] + k,
                Op::KSub { dst, k, a } => slots[dst as usize] = k - slots[a as usize],
                Op::MulK { dst, a, k } => slots[dst as usize] = slots[a as usize] * k,
                Op::DivK { dst, a, k } => slots[dst as usize] = slots[a as usize] / k,
                Op::KDiv { dst, k, a } => slots[dst as usize] = k / slots[a as usize],
                Op::Pow { dst, a, b } => {
                    slots[dst as usize] = pow(slots[a as usize], slots[b as usize]);
                }
                Op::PowK { dst, a, k } => slots[dst as usize] = slots[a as usize].powf(k),
                Op::PowI { dst, a, n } => slots[dst as usize] = slots[a as usize].powi(n),
                Op::Call1 { dst, f, a } => slots[dst as usize] = f.apply1(slots[a as usize]),
                Op::Call2 { dst, f, a, b } => {
                    slots[dst as usize] = f.apply2(slots[a as usize], slots[b as usize]);
                }
            }
        }
    }
}

impl fmt::Display for Tape {
    /// A listing, one op per line (`s5 = s3 * 0.5`), for debugging.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "tape: {} ops, {} slots ({} fixed)",
            self.ops.len(),
            self.n_slots,
            self.n_fixed
        )?;
        for op in &self.ops {
            writeln!(f, "  {op}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Var, parse};
    use super::*;

    /// A tiny linear congruential generator (Knuth's MMIX constants), so the
    /// tests need no rand crate and always see the same numbers.
    struct Lcg(u64);

    impl Lcg {
        /// Uniform in `[lo, hi)`.
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

    /// Slots: 0 = t, 1 = e, 2 = f, 3 = p, 4 = q, 5 = x (a parameter-looking
    /// input), 6 = the result; other parameters are constants.
    fn resolver(
        params: &'static [(&'static str, f64)],
    ) -> impl FnMut(&Expr) -> Result<Leaf, String> {
        |leaf: &Expr| match leaf {
            Expr::Time => Ok(Leaf::Slot(0)),
            Expr::Local(n) => match n.as_str() {
                "e" => Ok(Leaf::Slot(1)),
                "f" => Ok(Leaf::Slot(2)),
                "p" => Ok(Leaf::Slot(3)),
                _ => Ok(Leaf::Slot(4)),
            },
            Expr::Param(n) if n == "x" => Ok(Leaf::Slot(5)),
            Expr::Param(n) => params
                .iter()
                .find(|(name, _)| name == n)
                .map(|(_, v)| Leaf::Const(*v))
                .ok_or_else(|| format!("unknown parameter '{n}'")),
            other => Err(format!("unexpected leaf {other}")),
        }
    }

    const EXPRS: [&str; 20] = [
        "tau_c * tanh(f / 0.01) + b * f",
        "p / L0 * (1 + (p / psi_s)^2)",
        "V0 * sin(2 * pi * 50 * t)",
        "e - f - p - q",
        "-e - f + 3 - x",
        "-(e + 1) * -f * 2",
        "e / f / p",
        "2 / f + f / 2 + b / L0",
        "e^2 - f^3 + p^-2 + q^0.5 + x^e",
        "2^x + 2^3^0.5",
        "sqrt(abs(e)) * exp(-t / tau_c) - ln(abs(q) + 1)",
        "sign(f) * min(e, 0) + max(p, q) - atan2(f, 1) + atan2(1, x)",
        "sin(e) * cos(f) - tan(p) * atan(q)",
        "R / L * p",
        "-p",
        "x",
        "b * L0",
        "e * f * p * q * x * t",
        "((e + f) * (p - q)) / ((x + 1) * (t + 2)) - e",
        "-(-(e))",
    ];

    const PARAMS: [(&str, f64); 7] = [
        ("tau_c", 0.2),
        ("b", 0.05),
        ("L0", 0.01),
        ("psi_s", 0.3),
        ("V0", 24.0),
        ("R", 1.5),
        ("L", 2e-3),
    ];

    fn tree_value(e: &Expr, slots: &[f64]) -> Option<f64> {
        e.eval(&|leaf: &Expr| match leaf {
            Expr::Time => Some(slots[0]),
            Expr::Local(n) => Some(match n.as_str() {
                "e" => slots[1],
                "f" => slots[2],
                "p" => slots[3],
                _ => slots[4],
            }),
            Expr::Param(n) if n == "x" => Some(slots[5]),
            Expr::Param(n) => PARAMS.iter().find(|(m, _)| m == n).map(|(_, v)| *v),
            _ => None,
        })
    }

    #[test]
    fn tape_matches_tree_on_random_inputs() {
        let mut rng = Lcg(0x5eed);
        for src in EXPRS {
            let e = parse(src).unwrap();
            let mut builder = TapeBuilder::new(7);
            builder.assign(6, &e, &mut resolver(&PARAMS)).unwrap();
            let tape = builder.finish();
            let mut slots = vec![0.0; tape.n_slots()];
            for _ in 0..50 {
                for s in &mut slots[..6] {
                    *s = rng.uniform(-3.0, 3.0);
                }
                let want = tree_value(&e, &slots).unwrap();
                tape.eval(&mut slots);
                let got = slots[6];
                // 1e-12 relative: constant gathering reassociates a few roundings.
                let ok = (want.is_nan() && got.is_nan())
                    || (want - got).abs() <= 1e-12 * (1.0 + want.abs().max(got.abs()));
                assert!(ok, "{src}: tree {want} vs tape {got}\n{tape}");
            }
        }
    }

    #[test]
    fn constant_factors_fold_into_one_mulk() {
        let mut builder = TapeBuilder::new(7);
        builder
            .assign(6, &parse("2*3*x").unwrap(), &mut resolver(&PARAMS))
            .unwrap();
        let tape = builder.finish();
        assert_eq!(
            tape.ops,
            [Op::MulK {
                dst: 6,
                a: 5,
                k: 6.0
            }]
        );
        assert_eq!(tape.n_slots(), 7, "no temporary needed");
    }

    #[test]
    fn parameter_only_expression_is_one_constant() {
        let mut builder = TapeBuilder::new(7);
        builder
            .assign(
                6,
                &parse("R / L * (1 + b)").unwrap(),
                &mut resolver(&PARAMS),
            )
            .unwrap();
        assert_eq!(
            builder.finish().ops,
            [Op::Const {
                dst: 6,
                k: 1.5 / 2e-3 * 1.05
            }]
        );
    }

    #[test]
    fn slot_copy_and_self_assignment() {
        let mut builder = TapeBuilder::new(7);
        let mut resolve = resolver(&PARAMS);
        builder
            .assign(6, &parse("x").unwrap(), &mut resolve)
            .unwrap();
        builder
            .assign(5, &parse("x").unwrap(), &mut resolve)
            .unwrap();
        assert_eq!(builder.finish().ops, [Op::Copy { dst: 6, a: 5 }]);
    }

    #[test]
    fn subtraction_chains_use_sub_ops() {
        let mut builder = TapeBuilder::new(7);
        builder
            .assign(6, &parse("e - f - p").unwrap(), &mut resolver(&PARAMS))
            .unwrap();
        let tape = builder.finish();
        assert_eq!(
            tape.ops,
            [
                Op::Sub { dst: 7, a: 1, b: 2 },
                Op::Sub { dst: 6, a: 7, b: 3 },
            ]
        );
    }

    #[test]
    fn temporaries_are_reused_across_assignments() {
        let e = parse("((e + f) * (p - q)) / ((x + 1) * (t + 2))").unwrap();
        let compile = |times: usize| {
            let mut builder = TapeBuilder::new(7);
            let mut resolve = resolver(&PARAMS);
            for _ in 0..times {
                builder.assign(6, &e, &mut resolve).unwrap();
            }
            builder.finish()
        };
        let (once, six) = (compile(1), compile(6));
        assert_eq!(six.n_ops(), 6 * once.n_ops());
        assert_eq!(six.n_slots(), once.n_slots());
        assert_eq!(once.n_slots(), 7 + 3, "{once}");
    }

    #[test]
    fn assignments_see_earlier_results() {
        // A DC motor's causal assignments: slots 0 = p3 (state), 1 = p8 (state),
        // 2 = V (input), 3 = f3, 4 = e2, 5 = f8, 6 = e6, 7 = dp3, 8 = dp8.
        let (r, l, k, j, b) = (1.2, 2e-3, 0.05, 1e-4, 1e-5);
        let slot_of = |v: Var| match v {
            Var::P(3) => 0,
            Var::P(8) => 1,
            Var::F(3) => 3,
            Var::E(2) => 4,
            Var::F(8) => 5,
            Var::E(6) => 6,
            Var::Pdot(3) => 7,
            _ => 8,
        };
        let program = [
            (Var::F(3), "p3 / L"),
            (Var::E(2), "R * f3"),
            (Var::F(8), "p8 / J"),
            (Var::E(6), "b * f8"),
            (Var::Pdot(3), "V - e2 - k * f8"),
            (Var::Pdot(8), "k * f3 - e6"),
        ];
        let mut builder = TapeBuilder::new(9);
        let mut resolve = |leaf: &Expr| -> Result<Leaf, String> {
            match leaf {
                Expr::Param(n) => Ok(match n.as_str() {
                    "R" => Leaf::Const(r),
                    "L" => Leaf::Const(l),
                    "k" => Leaf::Const(k),
                    "J" => Leaf::Const(j),
                    "b" => Leaf::Const(b),
                    "V" => Leaf::Slot(2),
                    "p3" => Leaf::Slot(0),
                    "p8" => Leaf::Slot(1),
                    "f3" => Leaf::Slot(3),
                    "e2" => Leaf::Slot(4),
                    "f8" => Leaf::Slot(5),
                    "e6" => Leaf::Slot(6),
                    other => return Err(format!("unknown '{other}'")),
                }),
                other => Err(format!("unexpected {other}")),
            }
        };
        for (v, src) in program {
            builder
                .assign(slot_of(v), &parse(src).unwrap(), &mut resolve)
                .unwrap();
        }
        let tape = builder.finish();
        assert_eq!(tape.n_slots(), 9 + 2, "two temporaries for dp3:\n{tape}");
        assert_eq!(tape.n_ops(), 9, "{tape}");
        let mut slots = vec![0.0; tape.n_slots()];
        slots[..3].copy_from_slice(&[1e-3, 2e-6, 12.0]);
        tape.eval(&mut slots);
        let (i, w) = (1e-3 / l, 2e-6 / j);
        assert_eq!(slots[7], 12.0 - r * i - k * w);
        assert_eq!(slots[8], k * i - b * w);
    }

    #[test]
    fn resolve_error_is_returned_and_builder_unchanged() {
        let mut builder = TapeBuilder::new(7);
        let mut resolve = resolver(&PARAMS);
        builder
            .assign(6, &parse("e + f").unwrap(), &mut resolve)
            .unwrap();
        let before = builder.clone();
        let err = builder
            .assign(6, &parse("(e + f) * (p + nope)").unwrap(), &mut resolve)
            .unwrap_err();
        assert_eq!(err, "unknown parameter 'nope'");
        assert_eq!(builder.ops, before.ops);
        assert_eq!(builder.free, before.free);
        assert_eq!(builder.high, before.high);
    }

    #[test]
    fn sign_of_zero_is_zero_on_tape() {
        let mut builder = TapeBuilder::new(7);
        builder
            .assign(6, &parse("sign(x)").unwrap(), &mut resolver(&PARAMS))
            .unwrap();
        let tape = builder.finish();
        let mut slots = vec![0.0; tape.n_slots()];
        tape.eval(&mut slots);
        assert_eq!(slots[6], 0.0);
    }

    #[test]
    fn tape_is_send_sync_and_small() {
        fn assert_send_sync<T: Send + Sync + Clone>() {}
        assert_send_sync::<Tape>();
        assert!(std::mem::size_of::<Op>() <= 24);
    }

    #[test]
    #[should_panic(expected = "caller-owned")]
    fn destination_must_be_fixed_slot() {
        let mut builder = TapeBuilder::new(2);
        let _ = builder.assign(2, &Expr::Num(1.0), &mut |_| Ok::<_, ()>(Leaf::Const(0.0)));
    }
}
