//! Symbolic algebra: [`Expr::simplify`] for printing derived equations, and
//! [`linear_form`] for reading the `A`/`B` coefficients off state equations.

use std::f64::consts::PI;

use super::{Expr, Func, pow, small_int};

impl Expr {
    /// A tidier equivalent expression, for printing derived equations.
    ///
    /// Bottom-up, it flattens nested sums and products; folds numeric
    /// constants (keeping π symbolic in products: `2*pi*50*t` → `100*pi*t`);
    /// drops `+ 0`, `* 1`, `/ 1`, `^ 1`; turns `x*0`, `0/x` into `0` and `x^0`
    /// into `1`; cancels `--x`; merges numeric factors of a product into one
    /// leading coefficient and pulls signs out of products and quotients
    /// (`(-1)*R*f` → `-(R*f)`, printed `-R*f`); distributes a minus over a
    /// parenthesized sum inside a sum (`a - (b - c)` → `a - b + c`); and adds up
    /// like terms (`x + 2*x` → `3*x`, `x - x` → `0`).
    ///
    /// Terms and factors otherwise keep their written order (the constant of
    /// a sum sits where the first number was, the coefficient of a product
    /// comes first), so a junction equation still reads `e1 - e2 - e4`.
    /// Folds that would produce a non-finite number (`1/0`) are left unfolded.
    /// The result has the same value up to rounding, except that `x*0`, `x - x`
    /// and `0/x` are `0` even where `x` is infinite or NaN.
    ///
    /// # Example
    ///
    /// ```
    /// # use modelgap_bond::expr::parse;
    /// let e = parse("(-1) * R * f + 0 - -(2 * 3 * x) / 1")?;
    /// assert_eq!(e.simplify().to_string(), "-R*f + 6*x");
    /// # Ok::<(), modelgap_bond::expr::ParseError>(())
    /// ```
    pub fn simplify(&self) -> Expr {
        match self {
            Expr::Num(_)
            | Expr::Param(_)
            | Expr::Input(_)
            | Expr::Var(_)
            | Expr::Local(_)
            | Expr::Time => self.clone(),
            Expr::Neg(x) => negate(x.simplify()),
            Expr::Add(ts) => sum(ts.iter().map(Expr::simplify)),
            Expr::Mul(fs) => product(fs.iter().map(Expr::simplify)),
            Expr::Div(a, b) => quotient(a.simplify(), b.simplify()),
            Expr::Pow(a, b) => power(a.simplify(), b.simplify()),
            Expr::Call(f, xs) => call(*f, xs.iter().map(Expr::simplify).collect()),
        }
    }
}

fn is_pi(v: f64) -> bool {
    v.abs() == PI
}

fn one_or(mut xs: Vec<Expr>, make: impl FnOnce(Vec<Expr>) -> Expr) -> Expr {
    if xs.len() == 1 {
        xs.swap_remove(0)
    } else {
        make(xs)
    }
}

/// A number, with `-0` written as `0`.
fn num(v: f64) -> Expr {
    Expr::Num(if v == 0.0 { 0.0 } else { v })
}

/// `-e` for a simplified `e`.
fn negate(e: Expr) -> Expr {
    match e {
        Expr::Num(v) => num(-v),
        Expr::Neg(x) => *x,
        e => Expr::Neg(Box::new(e)),
    }
}

/// A sum of simplified terms.
fn sum(terms: impl Iterator<Item = Expr>) -> Expr {
    fn flatten(e: Expr, negative: bool, out: &mut Vec<Expr>) {
        match e {
            Expr::Add(ts) => ts.into_iter().for_each(|t| flatten(t, negative, out)),
            Expr::Neg(x) if matches!(*x, Expr::Add(_)) => flatten(*x, !negative, out),
            t if negative => out.push(negate(t)),
            t => out.push(t),
        }
    }
    let mut flat = Vec::new();
    for t in terms {
        flatten(t, false, &mut flat);
    }

    // Like terms, in order of first appearance; `None` is the constant.
    let mut groups: Vec<(Option<Expr>, f64)> = Vec::new();
    for t in flat {
        let (c, rest) = split_coefficient(t);
        match groups.iter_mut().find(|(r, _)| *r == rest) {
            Some((_, acc)) => *acc += c,
            None => groups.push((rest, c)),
        }
    }
    let out: Vec<Expr> = groups
        .into_iter()
        .filter(|(_, c)| *c != 0.0)
        .map(|(rest, c)| match rest {
            None => num(c),
            Some(r) => product([Expr::Num(c), r].into_iter()),
        })
        .collect();
    if out.is_empty() {
        Expr::Num(0.0)
    } else {
        one_or(out, Expr::Add)
    }
}

/// A simplified term as `coefficient × rest`; `rest` is `None` for a number.
fn split_coefficient(t: Expr) -> (f64, Option<Expr>) {
    match t {
        Expr::Num(v) => (v, None),
        Expr::Neg(x) => {
            let (c, r) = split_coefficient(*x);
            (-c, r)
        }
        Expr::Mul(mut fs) => match fs.first() {
            Some(&Expr::Num(c)) if !is_pi(c) => {
                fs.remove(0);
                (c, Some(one_or(fs, Expr::Mul)))
            }
            _ => (1.0, Some(Expr::Mul(fs))),
        },
        t => (1.0, Some(t)),
    }
}

/// A product of simplified factors: `[coefficient] [pi…] rest…`, with the sign outside.
fn product(factors: impl Iterator<Item = Expr>) -> Expr {
    struct Acc {
        coef: f64,
        n_pi: usize,
        negative: bool,
        rest: Vec<Expr>,
    }
    fn absorb(e: Expr, acc: &mut Acc) {
        match e {
            Expr::Num(v) if is_pi(v) => {
                acc.n_pi += 1;
                acc.negative ^= v < 0.0;
            }
            Expr::Num(v) => acc.coef *= v,
            Expr::Neg(x) => {
                acc.negative = !acc.negative;
                absorb(*x, acc);
            }
            Expr::Mul(fs) => fs.into_iter().for_each(|f| absorb(f, acc)),
            e => acc.rest.push(e),
        }
    }
    let mut acc = Acc {
        coef: 1.0,
        n_pi: 0,
        negative: false,
        rest: Vec::new(),
    };
    factors.for_each(|f| absorb(f, &mut acc));
    if acc.coef == 0.0 {
        return Expr::Num(0.0);
    }
    if acc.coef < 0.0 {
        acc.coef = -acc.coef;
        acc.negative = !acc.negative;
    }
    let mut fs = Vec::with_capacity(acc.rest.len() + acc.n_pi + 1);
    if acc.coef != 1.0 || (acc.n_pi == 0 && acc.rest.is_empty()) {
        fs.push(Expr::Num(acc.coef));
    }
    fs.extend(std::iter::repeat_n(Expr::Num(PI), acc.n_pi));
    fs.extend(acc.rest);
    let e = one_or(fs, Expr::Mul);
    if acc.negative { negate(e) } else { e }
}

/// `a / b` for simplified operands.
fn quotient(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        (a, Expr::Num(1.0)) => a,
        (a, Expr::Num(-1.0)) => negate(a),
        (Expr::Num(x), Expr::Num(y)) if !is_pi(x) && !is_pi(y) && (x / y).is_finite() => num(x / y),
        (Expr::Num(0.0), _) => Expr::Num(0.0),
        (Expr::Neg(x), b) => negate(quotient(*x, b)),
        (a, Expr::Neg(y)) => negate(quotient(a, *y)),
        (Expr::Num(x), b) if x < 0.0 => negate(quotient(Expr::Num(-x), b)),
        (a, Expr::Num(y)) if y < 0.0 => negate(quotient(a, Expr::Num(-y))),
        (a, b) => Expr::Div(Box::new(a), Box::new(b)),
    }
}

/// `a ^ b` for simplified operands.
fn power(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        (_, Expr::Num(0.0)) | (Expr::Num(1.0), _) => Expr::Num(1.0),
        (a, Expr::Num(1.0)) => a,
        (Expr::Num(x), Expr::Num(y)) if !is_pi(x) && !is_pi(y) && pow(x, y).is_finite() => {
            num(pow(x, y))
        }
        (a, b) => Expr::Pow(Box::new(a), Box::new(b)),
    }
}

/// `f(args…)` for simplified arguments, folded when all are numbers.
fn call(f: Func, args: Vec<Expr>) -> Expr {
    let values: Option<Vec<f64>> = args
        .iter()
        .map(|a| match a {
            Expr::Num(v) => Some(*v),
            _ => None,
        })
        .collect();
    match values.and_then(|v| f.apply(&v)) {
        Some(v) if v.is_finite() => num(v),
        _ => Expr::Call(f, args),
    }
}

/// Splits `expr` into `Σ coeffs[i] * vars[i] + rest` when it is affine in `vars`.
///
/// `vars` are the leaves to solve for (usually [`Expr::Var`] states and
/// [`Expr::Input`] signals), matched with `==` against the subtrees of
/// `expr.simplify()`. The coefficients are simplified sums of monomials
/// (a signed number times parameters with integer powers, numerator factors
/// in written order, then denominator ones): `R/L`, `-k/J`, `1`,
/// `-(R1*J + b*L)/(L*J)` prints as `-R1/L - b/J`. `rest` is the simplified
/// part free of every listed leaf (`0` for a homogeneous equation).
///
/// Returns `None` if `expr` is not affine in `vars`: a product of two listed
/// leaves, a listed leaf inside a function call, a power, or a denominator.
///
/// # Example
///
/// ```
/// # use modelgap_bond::expr::{linear_form, parse, Expr};
/// let dp3 = parse("V - R/L*p3 - k/J*p8")?;
/// let vars = [Expr::param("p3"), Expr::param("p8"), Expr::param("V")];
/// let (coeffs, rest) = linear_form(&dp3, &vars).unwrap();
/// let shown: Vec<String> = coeffs.iter().map(ToString::to_string).collect();
/// assert_eq!(shown, ["-R/L", "-k/J", "1"]);
/// assert_eq!(rest, Expr::Num(0.0));
/// assert!(linear_form(&parse("tanh(p3)")?, &vars).is_none());
/// # Ok::<(), modelgap_bond::expr::ParseError>(())
/// ```
pub fn linear_form(expr: &Expr, vars: &[Expr]) -> Option<(Vec<Expr>, Expr)> {
    let lin = Lin::of(&expr.simplify(), vars)?;
    let coeffs = lin.coeffs.iter().map(Poly::to_expr).collect();
    Some((coeffs, lin.rest.simplify()))
}

/// `Σ coeffs[i] * vars[i] + rest` during [`linear_form`].
struct Lin {
    coeffs: Vec<Poly>,
    rest: Expr,
}

impl Lin {
    fn of(e: &Expr, vars: &[Expr]) -> Option<Lin> {
        let mentions = |e: &Expr| vars.iter().any(|v| e.contains(v));
        if let Some(i) = vars.iter().position(|v| v == e) {
            let mut coeffs = vec![Poly::zero(); vars.len()];
            coeffs[i] = Poly::constant(1.0);
            return Some(Lin {
                coeffs,
                rest: Expr::Num(0.0),
            });
        }
        if !mentions(e) {
            return Some(Lin {
                coeffs: vec![Poly::zero(); vars.len()],
                rest: e.clone(),
            });
        }
        match e {
            Expr::Neg(x) => {
                let inner = Lin::of(x, vars)?;
                Some(Lin {
                    coeffs: inner.coeffs.into_iter().map(Poly::neg).collect(),
                    rest: Expr::Neg(Box::new(inner.rest)),
                })
            }
            Expr::Add(ts) => {
                let mut coeffs = vec![Poly::zero(); vars.len()];
                let mut rest = Vec::with_capacity(ts.len());
                for t in ts {
                    let l = Lin::of(t, vars)?;
                    for (acc, c) in coeffs.iter_mut().zip(l.coeffs) {
                        acc.add(c);
                    }
                    rest.push(l.rest);
                }
                Some(Lin {
                    coeffs,
                    rest: Expr::Add(rest),
                })
            }
            Expr::Mul(fs) => {
                let mut hits = fs.iter().enumerate().filter(|(_, f)| mentions(f));
                let (i, _) = hits.next()?;
                if hits.next().is_some() {
                    return None; // a product of two listed leaves
                }
                let inner = Lin::of(&fs[i], vars)?;
                let others: Vec<Expr> = (fs.iter().enumerate())
                    .filter(|(j, _)| *j != i)
                    .map(|(_, f)| f.clone())
                    .collect();
                let k = Poly::of(&Expr::Mul(others));
                let mut rest = fs.clone();
                rest[i] = inner.rest;
                Some(Lin {
                    coeffs: inner.coeffs.iter().map(|c| c.mul(&k)).collect(),
                    rest: Expr::Mul(rest),
                })
            }
            Expr::Div(a, b) if !mentions(b) => {
                let inner = Lin::of(a, vars)?;
                let k = Poly::of(b).recip(b);
                Some(Lin {
                    coeffs: inner.coeffs.iter().map(|c| c.mul(&k)).collect(),
                    rest: Expr::Div(Box::new(inner.rest), b.clone()),
                })
            }
            _ => None,
        }
    }
}

/// Most terms a coefficient may expand to before a product is kept whole.
const MAX_TERMS: usize = 64;

/// `coef × Π base^exp`, bases being simplified expressions other than plain
/// numbers (π is a base, so `2*pi` stays symbolic), exponents non-zero.
#[derive(Clone, Debug, PartialEq)]
struct Monomial {
    coef: f64,
    factors: Vec<(Expr, i32)>,
}

impl Monomial {
    fn mul(&self, other: &Monomial) -> Monomial {
        let mut factors = self.factors.clone();
        for (base, k) in &other.factors {
            match factors.iter().position(|(b, _)| b == base) {
                Some(j) => {
                    factors[j].1 += k;
                    if factors[j].1 == 0 {
                        factors.remove(j);
                    }
                }
                None => factors.push((base.clone(), *k)),
            }
        }
        Monomial {
            coef: self.coef * other.coef,
            factors,
        }
    }

    /// Same factors, in any order.
    fn is_like(&self, other: &Monomial) -> bool {
        self.factors.len() == other.factors.len()
            && self.factors.iter().all(|f| other.factors.contains(f))
    }

    fn to_expr(&self) -> Expr {
        let c = self.coef.abs();
        let mut num = Vec::new();
        let mut den = Vec::new();
        if c != 1.0 {
            // x/4 reads better than 0.25*x.
            let inv = 1.0 / c;
            if c.fract() != 0.0 && inv.is_finite() && inv.fract() == 0.0 {
                den.push(Expr::Num(inv));
            } else {
                num.push(Expr::Num(c));
            }
        }
        for (base, k) in &self.factors {
            let power = |n: i32| match n {
                1 => base.clone(),
                n => Expr::Pow(Box::new(base.clone()), Box::new(Expr::Num(f64::from(n)))),
            };
            if *k > 0 {
                num.push(power(*k));
            } else {
                den.push(power(-k));
            }
        }
        let num = if num.is_empty() {
            Expr::Num(1.0)
        } else {
            one_or(num, Expr::Mul)
        };
        let e = if den.is_empty() {
            num
        } else {
            Expr::Div(Box::new(num), Box::new(one_or(den, Expr::Mul)))
        };
        if self.coef < 0.0 {
            Expr::Neg(Box::new(e))
        } else {
            e
        }
    }
}

/// A sum of [`Monomial`]s with like terms merged; empty is zero.
#[derive(Clone, Debug, PartialEq)]
struct Poly(Vec<Monomial>);

impl Poly {
    fn zero() -> Poly {
        Poly(Vec::new())
    }

    fn constant(c: f64) -> Poly {
        let mut p = Poly::zero();
        p.push(Monomial {
            coef: c,
            factors: Vec::new(),
        });
        p
    }

    fn atom(base: Expr, k: i32) -> Poly {
        Poly(vec![Monomial {
            coef: 1.0,
            factors: vec![(base, k)],
        }])
    }

    /// The normal form of a simplified expression free of the listed leaves.
    fn of(e: &Expr) -> Poly {
        match e {
            Expr::Num(v) if is_pi(*v) => Poly(vec![Monomial {
                coef: v.signum(),
                factors: vec![(Expr::Num(PI), 1)],
            }]),
            Expr::Num(v) => Poly::constant(*v),
            Expr::Neg(x) => Poly::of(x).neg(),
            Expr::Add(ts) => {
                let mut p = Poly::zero();
                for t in ts {
                    p.add(Poly::of(t));
                }
                p
            }
            Expr::Mul(fs) => {
                let mut p = Poly::constant(1.0);
                for f in fs {
                    let q = Poly::of(f);
                    if p.0.len() * q.0.len() > MAX_TERMS {
                        return Poly::atom(e.clone(), 1);
                    }
                    p = p.mul(&q);
                }
                p
            }
            Expr::Div(a, b) => Poly::of(a).mul(&Poly::of(b).recip(b)),
            Expr::Pow(a, b) => match (&**b, Poly::of(a)) {
                (Expr::Num(n), Poly(ms)) if ms.len() == 1 => match small_int(*n) {
                    Some(n) if ms[0].coef != 0.0 => Poly(vec![Monomial {
                        coef: ms[0].coef.powi(n),
                        factors: (ms[0].factors.iter())
                            .map(|(b, k)| (b.clone(), k * n))
                            .collect(),
                    }]),
                    _ => Poly::atom(e.clone(), 1),
                },
                (Expr::Num(n), _) => match small_int(*n) {
                    Some(n) => Poly::atom((**a).clone(), n),
                    None => Poly::atom(e.clone(), 1),
                },
                _ => Poly::atom(e.clone(), 1),
            },
            _ => Poly::atom(e.clone(), 1),
        }
    }

    fn push(&mut self, m: Monomial) {
        if m.coef == 0.0 {
            return;
        }
        match self.0.iter().position(|x| x.is_like(&m)) {
            Some(j) => {
                self.0[j].coef += m.coef;
                if self.0[j].coef == 0.0 {
                    self.0.remove(j);
                }
            }
            None => self.0.push(m),
        }
    }

    fn add(&mut self, other: Poly) {
        for m in other.0 {
            self.push(m);
        }
    }

    fn neg(mut self) -> Poly {
        for m in &mut self.0 {
            m.coef = -m.coef;
        }
        self
    }

    fn mul(&self, other: &Poly) -> Poly {
        let mut p = Poly::zero();
        for a in &self.0 {
            for b in &other.0 {
                p.push(a.mul(b));
            }
        }
        p
    }

    /// `1 / self`, where `original` is the expression `self` came from (kept
    /// whole as a denominator when `self` is not a single monomial).
    fn recip(&self, original: &Expr) -> Poly {
        match self.0.as_slice() {
            [m] => Poly(vec![Monomial {
                coef: 1.0 / m.coef,
                factors: m.factors.iter().map(|(b, k)| (b.clone(), -k)).collect(),
            }]),
            _ => Poly::atom(original.clone(), -1),
        }
    }

    fn to_expr(&self) -> Expr {
        match self.0.as_slice() {
            [] => Expr::Num(0.0),
            ms => Expr::Add(ms.iter().map(Monomial::to_expr).collect()).simplify(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Var, parse};
    use super::*;

    fn simp(src: &str) -> String {
        parse(src).unwrap().simplify().to_string()
    }

    #[test]
    fn simplify_examples() {
        let cases = [
            ("e1 - e2 - e4", "e1 - e2 - e4"),
            ("x + 0", "x"),
            ("0 + x + 0", "x"),
            ("1 * x", "x"),
            ("x * 0 * y", "0"),
            ("--x", "x"),
            ("-(-(-x))", "-x"),
            ("2 * 3 * x", "6*x"),
            ("x * 2 * y * 3", "6*x*y"),
            ("x / 1", "x"),
            ("(-1) * R * f", "-R*f"),
            ("R * (-f)", "-R*f"),
            ("-R * -f", "R*f"),
            ("(-a) / b", "-a/b"),
            ("a / (-b)", "-a/b"),
            ("a - (b - c)", "a - b + c"),
            ("a + (b + (c + d))", "a + b + c + d"),
            ("a * (b * c)", "a*b*c"),
            ("1 + x + 2", "3 + x"),
            ("x + 2 - x", "2"),
            ("x + 2*x - 4*x", "-x"),
            ("2 * pi * 50 * t", "100*pi*t"),
            ("pi * x + 2 * pi * x", "3*pi*x"),
            ("-pi", "-pi"),
            ("0 / x", "0"),
            ("x ^ 1", "x"),
            ("x ^ 0", "1"),
            ("2 ^ 10", "1024"),
            ("sin(0) + cos(0) * x", "x"),
            ("1 / 0", "1/0"),
            ("ln(-1)", "ln(-1)"),
            ("a - -b", "a + b"),
            ("V - R/L*p3 - k/J*p8", "V - R/L*p3 - k/J*p8"),
            ("p / L0 * (1 + (p / psi_s)^2)", "p/L0*(1 + (p/psi_s)^2)"),
            ("tau_c * tanh(f / 0.01) + b * f", "tau_c*tanh(f/0.01) + b*f"),
        ];
        for (src, want) in cases {
            assert_eq!(simp(src), want, "{src}");
        }
    }

    #[test]
    fn simplify_keeps_value_and_is_idempotent() {
        let laws = [
            "tau_c * tanh(f / 0.01) + b * f",
            "a - (b - 2*c) * 3 - -(d + 1) / -2",
            "x^2 * -3 * y / (2 * -z) + 0.5 * x",
            "-(a + b) * -(c - d) + a*b - b*a",
            "2 * pi * 50 * t + 1/2 + sqrt(4)",
            "max(-a, 2*3) + atan2(-y, -(-x))",
        ];
        for src in laws {
            let e = parse(src).unwrap();
            let s = e.simplify();
            assert_eq!(s.simplify(), s, "{src}");
            for point in 1..6 {
                let env = |leaf: &Expr| match leaf {
                    Expr::Param(n) | Expr::Local(n) => Some(
                        f64::from(point) * 0.7 + n.len() as f64 + f64::from(n.as_bytes()[0]) / 50.0,
                    ),
                    Expr::Time => Some(0.01 * f64::from(point)),
                    _ => None,
                };
                let (a, b) = (e.eval(&env).unwrap(), s.eval(&env).unwrap());
                // 1e-12 relative: a few reassociated roundings on values below 1e3.
                assert!(
                    (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                    "{src}: {a} vs {b}"
                );
            }
        }
    }

    /// `V - R/L*p3 - k/J*p8` with `p3`, `p8` bound to states and `V` to an input.
    fn bind(src: &str) -> Expr {
        parse(src).unwrap().map(&mut |e| match e {
            Expr::Param(n) if n == "p3" => Some(Expr::Var(Var::P(3))),
            Expr::Param(n) if n == "p8" => Some(Expr::Var(Var::P(8))),
            Expr::Param(n) if n == "V" => Some(Expr::input("V")),
            _ => None,
        })
    }

    fn state_vars() -> [Expr; 3] {
        [Expr::Var(Var::P(3)), Expr::Var(Var::P(8)), Expr::input("V")]
    }

    #[test]
    fn linear_form_reads_state_equation_coefficients() {
        let (coeffs, rest) = linear_form(&bind("V - R/L*p3 - k/J*p8"), &state_vars()).unwrap();
        let r_over_l = Expr::Div(Box::new(Expr::param("R")), Box::new(Expr::param("L")));
        let k_over_j = Expr::Div(Box::new(Expr::param("k")), Box::new(Expr::param("J")));
        assert_eq!(
            coeffs,
            [
                Expr::Neg(Box::new(r_over_l)),
                Expr::Neg(Box::new(k_over_j)),
                Expr::Num(1.0)
            ]
        );
        assert_eq!(rest, Expr::Num(0.0));
    }

    #[test]
    fn linear_form_normalizes_coefficients_to_monomials() {
        let cases = [
            ("k*p3/L - b*p8/J", ["k/L", "-b/J", "0"], "0"),
            ("(V - R*p3/L) / 2", ["-R/(2*L)", "0", "0.5"], "0"),
            ("p3 * R * L^-1 + 3", ["R/L", "0", "0"], "3"),
            ("-(p3 - p8) * c / (m * m)", ["-c/m^2", "c/m^2", "0"], "0"),
            ("a*p3 + b*p3 - a*p3 + 2*pi*p8", ["b", "2*pi", "0"], "0"),
            (
                "(R1 + R2) * p3 / L + sin(t) * V",
                ["R1/L + R2/L", "0", "sin(t)"],
                "0",
            ),
            ("p3 / (L + M) + g*m", ["1/(L + M)", "0", "0"], "g*m"),
            ("(V + 2*p8) * tau + x", ["0", "2*tau", "tau"], "x"),
        ];
        for (src, want, want_rest) in cases {
            let (coeffs, rest) =
                linear_form(&bind(src), &state_vars()).unwrap_or_else(|| panic!("{src} is affine"));
            let shown: Vec<String> = coeffs.iter().map(ToString::to_string).collect();
            assert_eq!(shown, want, "{src}");
            assert_eq!(rest.to_string(), want_rest, "{src}");
        }
    }

    #[test]
    fn linear_form_rejects_nonlinear_terms() {
        for src in [
            "p3*p8",
            "tanh(p3)",
            "1/p3",
            "p3^2",
            "2^p3",
            "V*p3",
            "(p3 + 1)*(p8 + 1)",
            "R / (L + p8)",
        ] {
            assert!(linear_form(&bind(src), &state_vars()).is_none(), "{src}");
        }
    }

    #[test]
    fn linear_form_reconstructs_the_expression() {
        let src = "(V - R*p3/L) * 3 / (2 + x) - k/J*p8 + sin(t)";
        let e = bind(src);
        let vars = state_vars();
        let (coeffs, rest) = linear_form(&e, &vars).unwrap();
        let rebuilt = coeffs
            .into_iter()
            .zip(vars)
            .fold(rest, |acc, (c, v)| acc + c * v);
        for point in 1..5 {
            let env = |leaf: &Expr| match leaf {
                Expr::Var(Var::P(n)) => Some(f64::from(*n) * 0.3 + f64::from(point)),
                Expr::Input(_) => Some(2.0 * f64::from(point)),
                Expr::Param(n) => Some(1.0 + n.len() as f64 + f64::from(point) * 0.1),
                Expr::Time => Some(0.5),
                _ => None,
            };
            let (a, b) = (e.eval(&env).unwrap(), rebuilt.eval(&env).unwrap());
            // 1e-12 relative: reassociated products and sums of order-1 values.
            assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{a} vs {b}");
        }
    }
}
