//! [`TimeExpr`]: an expression of the time `t` (s), as a scene file writes a rail's motion
//! (`0.03 * sin(2 * pi * 0.4 * t)`).
//!
//! Numbers, `t`, `pi`, `+ - * /`, powers (`^` or `**`, right-associative), parentheses and
//! the functions `sin cos tan asin acos atan sinh cosh tanh exp ln log10 sqrt abs sign
//! floor` (one argument) and `min max atan2` (two). A bad token is named with its column.

use std::fmt;

/// A parse error of a [`TimeExpr`]: the column (1-based, in characters) and what was
/// expected there.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct TimeExprError {
    /// 1-based column of the bad token.
    pub column: usize,
    /// What was expected and found.
    pub message: String,
}

#[derive(Clone, Debug, PartialEq)]
enum Node {
    Num(f64),
    T,
    Neg(Box<Node>),
    Bin(Op, Box<Node>, Box<Node>),
    Call(Func, Vec<Node>),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Func {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Log10,
    Sqrt,
    Abs,
    Sign,
    Floor,
    Min,
    Max,
    Atan2,
}

const FUNCS: [(&str, Func, usize); 19] = [
    ("sin", Func::Sin, 1),
    ("cos", Func::Cos, 1),
    ("tan", Func::Tan, 1),
    ("asin", Func::Asin, 1),
    ("acos", Func::Acos, 1),
    ("atan", Func::Atan, 1),
    ("sinh", Func::Sinh, 1),
    ("cosh", Func::Cosh, 1),
    ("tanh", Func::Tanh, 1),
    ("exp", Func::Exp, 1),
    ("ln", Func::Ln, 1),
    ("log10", Func::Log10, 1),
    ("sqrt", Func::Sqrt, 1),
    ("abs", Func::Abs, 1),
    ("sign", Func::Sign, 1),
    ("floor", Func::Floor, 1),
    ("min", Func::Min, 2),
    ("max", Func::Max, 2),
    ("atan2", Func::Atan2, 2),
];

/// An expression of the time `t` (see the [module docs](self)); it keeps its text, which
/// a scene file writes back unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeExpr {
    text: String,
    root: Node,
}

impl TimeExpr {
    /// Parses `text`.
    ///
    /// # Errors
    /// [`TimeExprError`] naming the column of the first bad token.
    pub fn parse(text: &str) -> Result<Self, TimeExprError> {
        let chars: Vec<char> = text.chars().collect();
        let mut p = Parser { chars, pos: 0 };
        let root = p.expr()?;
        p.skip_space();
        if p.pos < p.chars.len() {
            return Err(p.error(format!(
                "expected an operator or the end, found `{}`",
                p.chars[p.pos]
            )));
        }
        Ok(Self {
            text: text.trim().to_owned(),
            root,
        })
    }

    /// A constant.
    #[must_use]
    pub fn constant(value: f64) -> Self {
        Self {
            text: format!("{value:?}"),
            root: Node::Num(value),
        }
    }

    /// The value at time `t` (s); NaN or infinite where the expression is (`1 / t` at 0).
    #[must_use]
    pub fn eval(&self, t: f64) -> f64 {
        eval(&self.root, t)
    }

    /// The text it was parsed from.
    #[must_use]
    pub fn text(&self) -> &str {
        &self.text
    }
}

impl fmt::Display for TimeExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

fn eval(node: &Node, t: f64) -> f64 {
    match node {
        Node::Num(v) => *v,
        Node::T => t,
        Node::Neg(a) => -eval(a, t),
        Node::Bin(op, a, b) => {
            let (a, b) = (eval(a, t), eval(b, t));
            match op {
                Op::Add => a + b,
                Op::Sub => a - b,
                Op::Mul => a * b,
                Op::Div => a / b,
                Op::Pow => a.powf(b),
            }
        }
        Node::Call(func, args) => {
            let a = eval(&args[0], t);
            let b = || eval(&args[1], t);
            match func {
                Func::Sin => a.sin(),
                Func::Cos => a.cos(),
                Func::Tan => a.tan(),
                Func::Asin => a.asin(),
                Func::Acos => a.acos(),
                Func::Atan => a.atan(),
                Func::Sinh => a.sinh(),
                Func::Cosh => a.cosh(),
                Func::Tanh => a.tanh(),
                Func::Exp => a.exp(),
                Func::Ln => a.ln(),
                Func::Log10 => a.log10(),
                Func::Sqrt => a.sqrt(),
                Func::Abs => a.abs(),
                Func::Sign => {
                    if a == 0.0 {
                        0.0
                    } else {
                        a.signum()
                    }
                }
                Func::Floor => a.floor(),
                Func::Min => a.min(b()),
                Func::Max => a.max(b()),
                Func::Atan2 => a.atan2(b()),
            }
        }
    }
}

struct Parser {
    chars: Vec<char>,
    pos: usize,
}

impl Parser {
    fn error(&self, message: String) -> TimeExprError {
        TimeExprError {
            column: self.pos + 1,
            message,
        }
    }

    fn skip_space(&mut self) {
        while self.chars.get(self.pos).is_some_and(|c| c.is_whitespace()) {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_space();
        self.chars.get(self.pos).copied()
    }

    fn found(&mut self) -> String {
        match self.peek() {
            Some(c) => format!("`{c}`"),
            None => "the end".to_owned(),
        }
    }

    fn expr(&mut self) -> Result<Node, TimeExprError> {
        let mut left = self.term()?;
        loop {
            let op = match self.peek() {
                Some('+') => Op::Add,
                Some('-') => Op::Sub,
                _ => return Ok(left),
            };
            self.pos += 1;
            let right = self.term()?;
            left = Node::Bin(op, Box::new(left), Box::new(right));
        }
    }

    fn term(&mut self) -> Result<Node, TimeExprError> {
        let mut left = self.unary()?;
        loop {
            let op = match self.peek() {
                Some('*') if self.chars.get(self.pos + 1) != Some(&'*') => Op::Mul,
                Some('/') => Op::Div,
                _ => return Ok(left),
            };
            self.pos += 1;
            let right = self.unary()?;
            left = Node::Bin(op, Box::new(left), Box::new(right));
        }
    }

    fn unary(&mut self) -> Result<Node, TimeExprError> {
        match self.peek() {
            Some('-') => {
                self.pos += 1;
                Ok(Node::Neg(Box::new(self.unary()?)))
            }
            Some('+') => {
                self.pos += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Node, TimeExprError> {
        let base = self.atom()?;
        match self.peek() {
            Some('^') => self.pos += 1,
            Some('*') if self.chars.get(self.pos + 1) == Some(&'*') => self.pos += 2,
            _ => return Ok(base),
        }
        let exponent = self.unary()?;
        Ok(Node::Bin(Op::Pow, Box::new(base), Box::new(exponent)))
    }

    fn atom(&mut self) -> Result<Node, TimeExprError> {
        match self.peek() {
            Some('(') => {
                self.pos += 1;
                let inner = self.expr()?;
                if self.peek() != Some(')') {
                    let found = self.found();
                    return Err(self.error(format!("expected `)`, found {found}")));
                }
                self.pos += 1;
                Ok(inner)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(),
            Some(c) if c.is_ascii_alphabetic() || c == '_' => self.name(),
            _ => {
                let found = self.found();
                Err(self.error(format!(
                    "expected a number, `t`, `pi`, a function or `(`, found {found}"
                )))
            }
        }
    }

    fn number(&mut self) -> Result<Node, TimeExprError> {
        let start = self.pos;
        let digits = |p: &mut Self| {
            while p.chars.get(p.pos).is_some_and(char::is_ascii_digit) {
                p.pos += 1;
            }
        };
        digits(self);
        if self.chars.get(self.pos) == Some(&'.') {
            self.pos += 1;
            digits(self);
        }
        if matches!(self.chars.get(self.pos), Some('e' | 'E')) {
            let mark = self.pos;
            self.pos += 1;
            if matches!(self.chars.get(self.pos), Some('+' | '-')) {
                self.pos += 1;
            }
            if self.chars.get(self.pos).is_some_and(char::is_ascii_digit) {
                digits(self);
            } else {
                self.pos = mark;
            }
        }
        let text: String = self.chars[start..self.pos].iter().collect();
        text.parse().map(Node::Num).map_err(|_| TimeExprError {
            column: start + 1,
            message: format!("expected a number, found `{text}`"),
        })
    }

    fn name(&mut self) -> Result<Node, TimeExprError> {
        let start = self.pos;
        while self
            .chars
            .get(self.pos)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == '_')
        {
            self.pos += 1;
        }
        let name: String = self.chars[start..self.pos].iter().collect();
        match name.as_str() {
            "t" => return Ok(Node::T),
            "pi" => return Ok(Node::Num(std::f64::consts::PI)),
            _ => {}
        }
        let Some(&(_, func, arity)) = FUNCS.iter().find(|f| f.0 == name) else {
            let known: Vec<&str> = FUNCS.iter().map(|f| f.0).collect();
            return Err(TimeExprError {
                column: start + 1,
                message: format!(
                    "expected `t`, `pi` or a function ({}), found `{name}`",
                    known.join(", ")
                ),
            });
        };
        if self.peek() != Some('(') {
            let found = self.found();
            return Err(self.error(format!("expected `(` after `{name}`, found {found}")));
        }
        self.pos += 1;
        let mut args = vec![self.expr()?];
        while self.peek() == Some(',') {
            self.pos += 1;
            args.push(self.expr()?);
        }
        if self.peek() != Some(')') {
            let found = self.found();
            return Err(self.error(format!("expected `,` or `)`, found {found}")));
        }
        if args.len() != arity {
            return Err(TimeExprError {
                column: start + 1,
                message: format!(
                    "expected {arity} argument{} for `{name}`, found {}",
                    if arity == 1 { "" } else { "s" },
                    args.len()
                ),
            });
        }
        self.pos += 1;
        Ok(Node::Call(func, args))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(text: &str, t: f64) -> f64 {
        TimeExpr::parse(text).unwrap().eval(t)
    }

    #[test]
    fn expressions_evaluate_with_the_usual_precedence() {
        let pi = std::f64::consts::PI;
        assert_eq!(at("1 + 2 * 3", 0.0), 7.0);
        assert_eq!(at("(1 + 2) * 3", 0.0), 9.0);
        assert_eq!(at("-2^2", 0.0), -4.0);
        assert_eq!(at("2^3^2", 0.0), 512.0);
        assert_eq!(at("2**3", 0.0), 8.0);
        assert_eq!(at("8 / 2 / 2", 0.0), 2.0);
        assert_eq!(at("1e-3 * t", 2.0), 2e-3);
        assert_eq!(at("min(t, 1) + max(t, 3)", 2.0), 4.0);
        let v = at("0.03 * sin(2 * pi * 0.4 * t)", 0.625);
        assert!((v - 0.03 * (2.0 * pi * 0.4 * 0.625).sin()).abs() < 1e-15);
        assert_eq!(at(" t ", 4.5), 4.5);
        assert_eq!(at("sign(-3) + abs(-2) + floor(1.5)", 0.0), 2.0);
    }

    #[test]
    fn bad_expressions_name_the_column() {
        let e = TimeExpr::parse("0.03 * sine(t)").unwrap_err();
        assert_eq!(e.column, 8, "{e}");
        assert!(e.message.contains("found `sine`"), "{e}");
        let e = TimeExpr::parse("1 + ").unwrap_err();
        assert_eq!(e.column, 5, "{e}");
        let e = TimeExpr::parse("(t").unwrap_err();
        assert!(e.message.contains("expected `)`"), "{e}");
        let e = TimeExpr::parse("t t").unwrap_err();
        assert_eq!(e.column, 3, "{e}");
        let e = TimeExpr::parse("min(t)").unwrap_err();
        assert!(e.message.contains("2 arguments"), "{e}");
        let e = TimeExpr::parse("x").unwrap_err();
        assert_eq!(e.column, 1, "{e}");
        assert!(TimeExpr::parse("").is_err());
    }

    #[test]
    fn the_text_is_kept() {
        let e = TimeExpr::parse("  0.1 * t ").unwrap();
        assert_eq!(e.text(), "0.1 * t");
        assert_eq!(TimeExpr::parse(e.text()).unwrap(), e);
    }
}
