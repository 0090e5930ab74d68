//! [`Expr`] → text and LaTeX, with the fewest parentheses that keep the meaning.
//!
//! Text output parses back ([`parse`](super::parse)) to an expression with
//! the same value, except for bond-graph variables, whose names (`p3`, `dp3`)
//! read back as parameters.

use std::f64::consts::PI;
use std::fmt;

use super::{Expr, Func, Var};

/// Binding strength of the printed form of a node; an operand binding less
/// tightly than its context needs is parenthesized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Prec {
    Sum,
    Product,
    Unary,
    Power,
    Atom,
}

/// A printed operand with its binding strength.
struct Part {
    s: String,
    prec: Prec,
}

impl Part {
    fn new(s: String, prec: Prec) -> Part {
        Part { s, prec }
    }

    fn starts_negative(&self) -> bool {
        self.s.starts_with('-')
    }
}

/// Which notation to print in.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Style {
    Text,
    Latex,
}

impl Style {
    fn paren(self, s: &str) -> String {
        match self {
            Style::Text => format!("({s})"),
            Style::Latex => format!("\\left({s}\\right)"),
        }
    }

    fn paren_if(self, part: Part, cond: bool) -> String {
        if cond { self.paren(&part.s) } else { part.s }
    }
}

impl fmt::Display for Expr {
    /// Plain text: `e1 - e2 - e4`, `R*f2`, `p3/L`, `V - R/L*p3 - k/J*p8`,
    /// `V0*sin(100*pi*t)`; π prints as `pi`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&render(self, Style::Text).s)
    }
}

impl Expr {
    /// The expression in LaTeX math notation (without `$` delimiters).
    ///
    /// Quotients become `\frac{R}{L}`, variables `p_{3}`, `\dot{p}_{3}`,
    /// functions `\tanh\left(…\right)`, lower-case Greek names their letter
    /// (`beta` → `\beta`, `tau_L` → `\tau_{L}`), trailing digits a subscript
    /// (`V0` → `V_{0}`), and products are juxtaposed with thin spaces
    /// (`R\,f_{2}`).
    ///
    /// # Example
    ///
    /// ```
    /// # use modelgap_bond::expr::parse;
    /// assert_eq!(parse("R/L")?.to_latex(), r"\frac{R}{L}");
    /// assert_eq!(parse("tau_c*tanh(f/0.01)")?.to_latex(), r"\tau_{c}\,\tanh\left(\frac{f}{0.01}\right)");
    /// # Ok::<(), modelgap_bond::expr::ParseError>(())
    /// ```
    pub fn to_latex(&self) -> String {
        render(self, Style::Latex).s
    }
}

/// A bond-graph variable in LaTeX: `e_{2}`, `f_{2}`, `p_{3}`, `q_{5}`,
/// `\dot{p}_{3}`, `\dot{q}_{5}`.
pub fn var_latex(v: Var) -> String {
    match v {
        Var::E(n) => format!("e_{{{n}}}"),
        Var::F(n) => format!("f_{{{n}}}"),
        Var::P(n) => format!("p_{{{n}}}"),
        Var::Q(n) => format!("q_{{{n}}}"),
        Var::Pdot(n) => format!("\\dot{{p}}_{{{n}}}"),
        Var::Qdot(n) => format!("\\dot{{q}}_{{{n}}}"),
        Var::Y(n) => format!("y_{{{n}}}"),
    }
}

/// Magnitudes printed in positional notation; outside this range scientific
/// notation is shorter (`1e-6`, `2.5e20`).
const POSITIONAL: std::ops::Range<f64> = 1e-4..1e16;

fn num_text(v: f64) -> String {
    if v == PI {
        "pi".to_owned()
    } else if v == -PI {
        "-pi".to_owned()
    } else if v == 0.0 || !v.is_finite() || POSITIONAL.contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

fn num_latex(v: f64) -> Part {
    let sign = if v < 0.0 { "-" } else { "" };
    let a = v.abs();
    if a == PI {
        return Part::new(format!("{sign}\\pi"), prec_of_sign(v));
    }
    if a == 0.0 || !a.is_finite() || POSITIONAL.contains(&a) {
        return Part::new(format!("{v}"), prec_of_sign(v));
    }
    let sci = format!("{a:e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    if mantissa == "1" {
        Part::new(format!("{sign}10^{{{exp}}}"), prec_of_sign(v))
    } else {
        Part::new(
            format!("{sign}{mantissa} \\cdot 10^{{{exp}}}"),
            Prec::Product,
        )
    }
}

fn prec_of_sign(v: f64) -> Prec {
    if v.is_sign_negative() && v != 0.0 {
        Prec::Unary
    } else {
        Prec::Atom
    }
}

/// The Greek letters LaTeX has commands for (lower case, then the upper-case
/// ones that differ from Latin letters).
const GREEK: &[&str] = &[
    "alpha",
    "beta",
    "gamma",
    "delta",
    "epsilon",
    "varepsilon",
    "zeta",
    "eta",
    "theta",
    "vartheta",
    "iota",
    "kappa",
    "lambda",
    "mu",
    "nu",
    "xi",
    "pi",
    "rho",
    "sigma",
    "tau",
    "upsilon",
    "phi",
    "varphi",
    "chi",
    "psi",
    "omega",
    "Gamma",
    "Delta",
    "Theta",
    "Lambda",
    "Xi",
    "Pi",
    "Sigma",
    "Upsilon",
    "Phi",
    "Psi",
    "Omega",
    "varrho",
];

fn greek(s: &str) -> Option<String> {
    GREEK.contains(&s).then(|| format!("\\{s}"))
}

/// A subscript word: Greek letters as commands, single characters and
/// numbers as they are, longer words upright (`R_load` → `R_{\mathrm{load}}`).
fn subscript_word(s: &str) -> String {
    if let Some(g) = greek(s) {
        g
    } else if s.chars().count() <= 1 || s.chars().all(|c| c.is_ascii_digit()) {
        s.to_owned()
    } else {
        format!("\\mathrm{{{s}}}")
    }
}

/// True for a name the parser reads as one name token (`Tank1`, `R_a`).
fn is_identifier(name: &str) -> bool {
    name.chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Text set upright in LaTeX, with its special characters escaped.
fn latex_text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '_' | '#' | '$' | '%' | '&' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// A parameter, input or local name in LaTeX: `beta` → `\beta`,
/// `tau_L` → `\tau_{L}`, `psi_s` → `\psi_{s}`, `V0` → `V_{0}`,
/// `k_a_b` → `k_{a,b}`, `Kt` → `\mathit{Kt}`.
fn name_latex(name: &str) -> String {
    let (base, sub) = match name.split_once('_') {
        Some((base, sub)) if !base.is_empty() && !sub.is_empty() => (base, Some(sub.to_owned())),
        _ => (name, None),
    };
    let (base, sub) = match sub {
        Some(sub) => (base, Some(sub)),
        None => {
            // Trailing digits become the subscript: V0 → V_{0}.
            let stem = base.trim_end_matches(|c: char| c.is_ascii_digit());
            if !stem.is_empty() && stem.len() < base.len() && !stem.ends_with('_') {
                (stem, Some(base[stem.len()..].to_owned()))
            } else {
                (base, None)
            }
        }
    };
    let base_tex = if let Some(g) = greek(base) {
        g
    } else if base.chars().count() == 1 {
        base.to_owned()
    } else {
        format!("\\mathit{{{}}}", base.replace('_', "\\_"))
    };
    match sub {
        Some(sub) => {
            let words: Vec<String> = sub.split('_').map(subscript_word).collect();
            format!("{base_tex}_{{{}}}", words.join(","))
        }
        None => base_tex,
    }
}

/// For a term of a sum that prints with a leading minus, the term without
/// it (`-x` → `x`, `-2*x` → `2*x`, `-3` → `3`).
fn negated_term(e: &Expr) -> Option<Expr> {
    match e {
        Expr::Neg(x) => Some((**x).clone()),
        Expr::Num(v) if *v < 0.0 => Some(Expr::Num(-v)),
        Expr::Mul(fs) => match fs.split_first() {
            Some((Expr::Num(v), rest)) if *v < 0.0 => {
                let mut out = Vec::with_capacity(fs.len());
                if *v != -1.0 || rest.is_empty() {
                    out.push(Expr::Num(-v));
                }
                out.extend(rest.iter().cloned());
                Some(if out.len() == 1 {
                    out.swap_remove(0)
                } else {
                    Expr::Mul(out)
                })
            }
            Some((Expr::Neg(x), rest)) => {
                let mut out = vec![(**x).clone()];
                out.extend(rest.iter().cloned());
                Some(Expr::Mul(out))
            }
            _ => None,
        },
        Expr::Div(a, b) => negated_term(a).map(|a| Expr::Div(Box::new(a), b.clone())),
        _ => None,
    }
}

fn render(e: &Expr, style: Style) -> Part {
    match e {
        Expr::Num(v) => match style {
            Style::Text => {
                let s = num_text(*v);
                let prec = if s.starts_with('-') {
                    Prec::Unary
                } else {
                    Prec::Atom
                };
                Part::new(s, prec)
            }
            Style::Latex => num_latex(*v),
        },
        Expr::Local(n) if super::split_signal(n).is_some() => {
            let (element, var) = super::split_signal(n).unwrap_or_default();
            match style {
                Style::Text if is_identifier(element) => Part::new(n.clone(), Prec::Atom),
                Style::Text => Part::new(format!("'{element}'.{var}"), Prec::Atom),
                Style::Latex => Part::new(
                    format!("{var}_{{\\mathrm{{{}}}}}", latex_text(element)),
                    Prec::Atom,
                ),
            }
        }
        Expr::Param(n) | Expr::Input(n) | Expr::Local(n) => match style {
            Style::Text => Part::new(n.clone(), Prec::Atom),
            Style::Latex => Part::new(name_latex(n), Prec::Atom),
        },
        Expr::Var(v) => match style {
            Style::Text => Part::new(v.to_string(), Prec::Atom),
            Style::Latex => Part::new(var_latex(*v), Prec::Atom),
        },
        Expr::Time => Part::new("t".to_owned(), Prec::Atom),
        Expr::Neg(x) => {
            let inner = render(x, style);
            let wrap = inner.prec <= Prec::Sum || inner.starts_negative();
            Part::new(format!("-{}", style.paren_if(inner, wrap)), Prec::Unary)
        }
        Expr::Add(terms) => {
            let Some((first, rest)) = terms.split_first() else {
                return Part::new("0".to_owned(), Prec::Atom);
            };
            if rest.is_empty() {
                return render(first, style);
            }
            let mut s = render(first, style).s;
            for t in rest {
                if let Some(abs) = negated_term(t) {
                    let p = render(&abs, style);
                    let wrap = p.prec <= Prec::Sum || p.starts_negative();
                    s.push_str(" - ");
                    s.push_str(&style.paren_if(p, wrap));
                } else {
                    let p = render(t, style);
                    let wrap = p.starts_negative();
                    s.push_str(" + ");
                    s.push_str(&style.paren_if(p, wrap));
                }
            }
            Part::new(
                s,
                if terms.len() == 1 {
                    Prec::Atom
                } else {
                    Prec::Sum
                },
            )
        }
        Expr::Mul(factors) => {
            match factors.as_slice() {
                [] => return Part::new("1".to_owned(), Prec::Atom),
                [only] => return render(only, style),
                _ => {}
            }
            let mut s = String::new();
            let mut prev_numeric = false;
            for (i, x) in factors.iter().enumerate() {
                let p = render(x, style);
                let wrap = p.prec <= Prec::Sum || (i > 0 && p.starts_negative());
                let numeric = matches!(x, Expr::Num(v) if *v != PI && *v != -PI);
                if i > 0 {
                    s.push_str(match style {
                        Style::Text => "*",
                        Style::Latex if numeric => " \\cdot ",
                        Style::Latex if prev_numeric => " ",
                        Style::Latex => "\\,",
                    });
                }
                s.push_str(&style.paren_if(p, wrap));
                prev_numeric = numeric;
            }
            Part::new(s, Prec::Product)
        }
        Expr::Div(a, b) => {
            let (pa, pb) = (render(a, style), render(b, style));
            match style {
                Style::Text => {
                    let wa = pa.prec <= Prec::Sum;
                    let wb = pb.prec < Prec::Power;
                    Part::new(
                        format!("{}/{}", style.paren_if(pa, wa), style.paren_if(pb, wb)),
                        Prec::Product,
                    )
                }
                Style::Latex => Part::new(format!("\\frac{{{}}}{{{}}}", pa.s, pb.s), Prec::Product),
            }
        }
        Expr::Pow(a, b) => {
            let (pa, pb) = (render(a, style), render(b, style));
            let wa = pa.prec < Prec::Atom;
            match style {
                Style::Text => {
                    let wb = pb.prec < Prec::Power;
                    Part::new(
                        format!("{}^{}", style.paren_if(pa, wa), style.paren_if(pb, wb)),
                        Prec::Power,
                    )
                }
                Style::Latex => Part::new(
                    format!("{{{}}}^{{{}}}", style.paren_if(pa, wa), pb.s),
                    Prec::Power,
                ),
            }
        }
        Expr::Call(f, args) => {
            let parts: Vec<String> = args.iter().map(|x| render(x, style).s).collect();
            let args = parts.join(", ");
            let s = match style {
                Style::Text => format!("{}({args})", f.name()),
                Style::Latex => match f {
                    Func::Sqrt => format!("\\sqrt{{{args}}}"),
                    Func::Abs => format!("\\left|{args}\\right|"),
                    _ => format!("{}\\left({args}\\right)", func_latex(*f)),
                },
            };
            Part::new(s, Prec::Atom)
        }
    }
}

fn func_latex(f: Func) -> &'static str {
    match f {
        Func::Sin => "\\sin",
        Func::Cos => "\\cos",
        Func::Tan => "\\tan",
        Func::Tanh => "\\tanh",
        Func::Exp => "\\exp",
        Func::Ln => "\\ln",
        Func::Sqrt => "\\sqrt",
        Func::Abs => "\\operatorname{abs}",
        Func::Sign => "\\operatorname{sign}",
        Func::Atan => "\\arctan",
        Func::Min => "\\min",
        Func::Max => "\\max",
        Func::Atan2 => "\\operatorname{atan2}",
        Func::Quantise => "\\operatorname{quantise}",
    }
}

#[cfg(test)]
mod tests {
    use super::super::parse;
    use super::*;

    /// Deterministic, mostly positive leaf values, different at each `point`.
    fn env(point: u32) -> impl Fn(&Expr) -> Option<f64> {
        move |e: &Expr| {
            let key = match e {
                Expr::Param(n) | Expr::Input(n) | Expr::Local(n) => n.clone(),
                Expr::Var(v) => v.to_string(),
                Expr::Time => "t".to_owned(),
                _ => return None,
            };
            let h = key
                .bytes()
                .fold(u64::from(point) * 7919 + 17, |h, b| h * 31 + u64::from(b));
            Some(0.3 + (h % 1000) as f64 / 250.0)
        }
    }

    /// Same value (NaNs equal) within a few ulps of reassociation.
    fn same(a: Option<f64>, b: Option<f64>) -> bool {
        match (a, b) {
            (Some(a), Some(b)) if a.is_nan() && b.is_nan() => true,
            // 1e-12 relative: a handful of roundings on values of order 1..1e3.
            (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0),
            _ => false,
        }
    }

    const LAWS: [&str; 16] = [
        "tau_c * tanh(f / 0.01) + b * f",
        "p / L0 * (1 + (p / psi_s)^2)",
        "V0 * sin(2 * pi * 50 * t)",
        "e1 - e2 - e4",
        "a - (b - c) - -d",
        "-x^2 + (-x)^2 - x^-2",
        "a / (b * c) / (d / e)",
        "2^3^2 + (2^3)^2",
        "-(a + b) * -c",
        "a * (-b) / (-c)",
        "max(a, -b) + atan2(-y, x) + abs(-q)",
        "1e-6 * x + 2.5e20 / y + 0.5",
        "-(-(-x))",
        "sqrt(x) * exp(-t / tau) - ln(q) * sign(f - 1)",
        "(a + b)^(c - d) / -(e)",
        "x - 2*y + -3*z - (-4)",
    ];

    #[test]
    fn printed_text_parses_back_to_same_value() {
        for src in LAWS {
            let e = parse(src).unwrap();
            for printed in [e.to_string(), e.simplify().to_string()] {
                let back = parse(&printed).unwrap_or_else(|err| panic!("{src} → {printed}: {err}"));
                for point in 0..5 {
                    let env = env(point);
                    assert!(
                        same(e.eval(&env), back.eval(&env)),
                        "{src} → {printed}: {:?} vs {:?}",
                        e.eval(&env),
                        back.eval(&env)
                    );
                }
            }
        }
    }

    #[test]
    fn text_uses_minimal_parentheses() {
        let cases = [
            ("e1 - e2 - e4", "e1 - e2 - e4"),
            ("R * f2", "R*f2"),
            ("p3 / L", "p3/L"),
            ("V - R/L*p3 - k/J*p8", "V - R/L*p3 - k/J*p8"),
            ("-x^2", "-x^2"),
            ("(-x)^2", "(-x)^2"),
            ("a - (b - c)", "a - (b - c)"),
            ("a / (b * c)", "a/(b*c)"),
            ("a * (b + c)", "a*(b + c)"),
            ("2^3^2", "2^3^2"),
            ("(2^3)^2", "(2^3)^2"),
            ("x^(-1)", "x^(-1)"),
            ("a * -b", "a*(-b)"),
            ("a + -b", "a - b"),
            ("V0 * sin(2 * pi * 50 * t)", "V0*sin(2*pi*50*t)"),
            ("1e-6 + 2.5e20 + 0.001", "1e-6 + 2.5e20 + 0.001"),
        ];
        for (src, want) in cases {
            assert_eq!(parse(src).unwrap().to_string(), want, "{src}");
        }
    }

    #[test]
    fn var_names_follow_paper() {
        let e = Expr::Var(Var::Pdot(3))
            - Expr::Var(Var::E(1))
            - Expr::param("R") * Expr::Var(Var::F(2));
        assert_eq!(e.to_string(), "dp3 - e1 - R*f2");
        assert_eq!(var_latex(Var::Pdot(3)), r"\dot{p}_{3}");
        assert_eq!(var_latex(Var::E(2)), "e_{2}");
        assert_eq!(var_latex(Var::Q(5)), "q_{5}");
    }

    #[test]
    fn latex_of_quotient_is_frac() {
        assert_eq!(parse("R/L").unwrap().to_latex(), r"\frac{R}{L}");
    }

    #[test]
    fn latex_renders_greek_names() {
        let cases = [
            ("beta", r"\beta"),
            ("omega", r"\omega"),
            ("alpha", r"\alpha"),
            ("tau_L", r"\tau_{L}"),
            ("psi_s", r"\psi_{s}"),
            ("Omega", r"\Omega"),
            ("V0", "V_{0}"),
            ("omega0", r"\omega_{0}"),
            ("R_load", r"R_{\mathrm{load}}"),
            ("k_a_b", "k_{a,b}"),
            ("Kt", r"\mathit{Kt}"),
            ("betas", r"\mathit{betas}"),
        ];
        for (name, want) in cases {
            assert_eq!(name_latex(name), want, "{name}");
        }
    }

    #[test]
    fn latex_of_state_equation() {
        let e = Expr::input("V")
            - Expr::param("R") / Expr::param("L") * Expr::Var(Var::P(3))
            - Expr::param("k") / Expr::param("J") * Expr::Var(Var::P(8));
        assert_eq!(e.to_latex(), r"V - \frac{R}{L}\,p_{3} - \frac{k}{J}\,p_{8}");
        let law = parse("p / L0 * (1 + (p / psi_s)^2)").unwrap();
        assert_eq!(
            law.to_latex(),
            r"\frac{p}{L_{0}}\,\left(1 + {\left(\frac{p}{\psi_{s}}\right)}^{2}\right)"
        );
        assert_eq!(
            parse("2*pi*x - 1e-6*abs(y) + sqrt(z)").unwrap().to_latex(),
            r"2 \pi\,x - 10^{-6} \left|y\right| + \sqrt{z}"
        );
        assert_eq!(parse("-x*3").unwrap().to_latex(), r"-x \cdot 3");
    }
}
