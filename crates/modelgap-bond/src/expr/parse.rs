//! Text → [`Expr`]: the recursive-descent parser for laws in model files.
//!
//! Grammar (lowest precedence first):
//!
//! ```text
//! sum     := product (('+' | '-') product)*
//! product := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary ('^' unary)?          right-associative, tighter than unary minus
//! primary := number | name | signal | function '(' sum (',' sum)* ')' | '(' sum ')'
//! signal  := (name | "'" any name "'") '.' ('e' | 'f' | 'p' | 'q')
//! ```
//!
//! A signal names a variable of another element (`Tank1.q`, `R2.f`,
//! `'1e'.f` for a name that is not an identifier): a law that reads it is a
//! modulated law, as 20-sim's activated bonds and modulated sources.

use std::f64::consts::PI;

use super::{Expr, Func};

/// Deepest nesting of parentheses, calls and unary operators accepted;
/// keeps hostile input from overflowing the stack.
const MAX_DEPTH: usize = 200;

/// Why a law could not be parsed, and where.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message} at column {column}")]
pub struct ParseError {
    /// 1-based column (in characters) of the offending token; one past the
    /// last character for an unexpected end of input.
    pub column: usize,
    /// What was expected and what was found, lowercase, without the column.
    pub message: String,
}

/// Parses a law such as `tau_c * tanh(f / 0.01) + b * f`.
///
/// Names are classified as they are read: `e`, `f`, `p`, `q` become
/// [`Expr::Local`], `t` becomes [`Expr::Time`], `pi` becomes the number π,
/// and every other name a [`Expr::Param`] (the caller turns those that name
/// input signals into [`Expr::Input`] with [`Expr::map`]). Function calls are
/// limited to [`Func`]; `^` is right-associative and binds tighter than unary
/// minus (`-x^2 = -(x^2)`, `2^3^2 = 512`).
///
/// # Errors
///
/// [`ParseError`] with the column of the first bad token: an empty input, an
/// unexpected character or token, unbalanced parentheses, an unknown function,
/// a call with the wrong number of arguments, a number literal that is not
/// finite (`1e999`), or nesting deeper than 200 levels.
///
/// # Example
///
/// ```
/// # use modelgap_bond::expr::parse;
/// let law = parse("p / L0 * (1 + (p / psi_s)^2)")?;
/// assert_eq!(law.to_string(), "p/L0*(1 + (p/psi_s)^2)");
/// let err = parse("R * (f").unwrap_err();
/// assert_eq!(err.to_string(), "expected ')' but found end of input at column 7");
/// # Ok::<(), modelgap_bond::expr::ParseError>(())
/// ```
pub fn parse(src: &str) -> Result<Expr, ParseError> {
    let tokens = lex(src)?;
    let mut p = Parser {
        tokens,
        pos: 0,
        depth: 0,
    };
    let e = p.sum()?;
    let tok = p.peek();
    if tok.kind != Kind::End {
        return Err(tok.error(format!(
            "expected an operator or end of input but found {}",
            tok.describe()
        )));
    }
    Ok(e)
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Num(f64),
    Name,
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    Comma,
    /// `.` between an element name and the variable it names.
    Dot,
    /// An element name in single quotes (`'1e'`), text without the quotes.
    Quoted,
    End,
}

#[derive(Clone, Debug)]
struct Token {
    kind: Kind,
    /// The source text of the token (empty for the end).
    text: String,
    /// 1-based character column.
    column: usize,
}

impl Token {
    fn describe(&self) -> String {
        match self.kind {
            Kind::End => "end of input".to_owned(),
            Kind::Num(_) => format!("number '{}'", self.text),
            Kind::Name => format!("name '{}'", self.text),
            Kind::Quoted => format!("quoted name '{}'", self.text),
            _ => format!("'{}'", self.text),
        }
    }

    fn error(&self, message: String) -> ParseError {
        ParseError {
            column: self.column,
            message,
        }
    }
}

fn lex(src: &str) -> Result<Vec<Token>, ParseError> {
    let chars: Vec<char> = src.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let column = i + 1;
        let digit_at = |j: usize| chars.get(j).is_some_and(char::is_ascii_digit);
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let kind = match c {
            '+' => Kind::Plus,
            '-' => Kind::Minus,
            '*' => Kind::Star,
            '/' => Kind::Slash,
            '^' => Kind::Caret,
            '(' => Kind::LParen,
            ')' => Kind::RParen,
            ',' => Kind::Comma,
            '.' if !digit_at(i + 1) => Kind::Dot,
            '\'' => {
                let Some(len) = chars[i + 1..].iter().position(|&c| c == '\'') else {
                    return Err(ParseError {
                        column,
                        message: "expected a closing ' after the quoted element name".to_string(),
                    });
                };
                let text: String = chars[i + 1..i + 1 + len].iter().collect();
                if text.trim().is_empty() {
                    return Err(ParseError {
                        column,
                        message: "expected an element name between the quotes".to_string(),
                    });
                }
                tokens.push(Token {
                    kind: Kind::Quoted,
                    text,
                    column,
                });
                i += len + 2;
                continue;
            }
            _ if c.is_ascii_digit() || (c == '.' && digit_at(i + 1)) => {
                let start = i;
                while digit_at(i) {
                    i += 1;
                }
                if chars.get(i) == Some(&'.') {
                    i += 1;
                    while digit_at(i) {
                        i += 1;
                    }
                }
                if matches!(chars.get(i), Some('e' | 'E')) {
                    let sign = usize::from(matches!(chars.get(i + 1), Some('+' | '-')));
                    if !digit_at(i + 1 + sign) {
                        let text: String = chars[start..i + 1 + sign].iter().collect();
                        return Err(ParseError {
                            column: i + 2 + sign,
                            message: format!("expected digits in the exponent of '{text}'"),
                        });
                    }
                    i += 1 + sign;
                    while digit_at(i) {
                        i += 1;
                    }
                }
                let text: String = chars[start..i].iter().collect();
                let value = text.parse::<f64>().map_err(|e| ParseError {
                    column,
                    message: format!("expected a number but found '{text}' ({e})"),
                })?;
                if !value.is_finite() {
                    return Err(ParseError {
                        column,
                        message: format!("expected a finite number but found '{text}'"),
                    });
                }
                tokens.push(Token {
                    kind: Kind::Num(value),
                    text,
                    column,
                });
                continue;
            }
            _ if c.is_ascii_alphabetic() || c == '_' => {
                let start = i;
                while chars
                    .get(i)
                    .is_some_and(|c| c.is_ascii_alphanumeric() || *c == '_')
                {
                    i += 1;
                }
                tokens.push(Token {
                    kind: Kind::Name,
                    text: chars[start..i].iter().collect(),
                    column,
                });
                continue;
            }
            _ => {
                return Err(ParseError {
                    column,
                    message: format!(
                        "expected a number, a name, an operator or a parenthesis but found '{c}'"
                    ),
                });
            }
        };
        tokens.push(Token {
            kind,
            text: c.to_string(),
            column,
        });
        i += 1;
    }
    tokens.push(Token {
        kind: Kind::End,
        text: String::new(),
        column: chars.len() + 1,
    });
    Ok(tokens)
}

struct Parser {
    tokens: Vec<Token>,
    pos: usize,
    depth: usize,
}

impl Parser {
    fn peek(&self) -> &Token {
        // `lex` always ends the list with `End`, and `bump` never moves past it.
        &self.tokens[self.pos.min(self.tokens.len() - 1)]
    }

    fn bump(&mut self) -> Token {
        let tok = self.peek().clone();
        if tok.kind != Kind::End {
            self.pos += 1;
        }
        tok
    }

    fn expect(&mut self, kind: Kind, what: &str) -> Result<Token, ParseError> {
        let tok = self.bump();
        if tok.kind == kind {
            Ok(tok)
        } else {
            Err(tok.error(format!("expected {what} but found {}", tok.describe())))
        }
    }

    fn descend(&mut self) -> Result<(), ParseError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.peek().error(format!(
                "expected at most {MAX_DEPTH} levels of nesting but found more"
            )));
        }
        Ok(())
    }

    fn sum(&mut self) -> Result<Expr, ParseError> {
        let mut terms = vec![self.product()?];
        loop {
            match self.peek().kind {
                Kind::Plus => {
                    self.bump();
                    terms.push(self.product()?);
                }
                Kind::Minus => {
                    self.bump();
                    terms.push(Expr::Neg(Box::new(self.product()?)));
                }
                _ => break,
            }
        }
        Ok(if terms.len() == 1 {
            terms.swap_remove(0)
        } else {
            Expr::Add(terms)
        })
    }

    fn product(&mut self) -> Result<Expr, ParseError> {
        let mut acc = self.unary()?;
        loop {
            match self.peek().kind {
                Kind::Star => {
                    self.bump();
                    let rhs = self.unary()?;
                    acc = match acc {
                        Expr::Mul(mut xs) => {
                            xs.push(rhs);
                            Expr::Mul(xs)
                        }
                        lhs => Expr::Mul(vec![lhs, rhs]),
                    };
                }
                Kind::Slash => {
                    self.bump();
                    let rhs = self.unary()?;
                    acc = Expr::Div(Box::new(acc), Box::new(rhs));
                }
                _ => return Ok(acc),
            }
        }
    }

    fn unary(&mut self) -> Result<Expr, ParseError> {
        match self.peek().kind {
            Kind::Minus | Kind::Plus => {
                let op = self.bump();
                self.descend()?;
                let operand = self.unary()?;
                self.depth -= 1;
                Ok(match (op.kind, operand) {
                    (Kind::Plus, e) => e,
                    (_, Expr::Num(v)) => Expr::Num(-v),
                    (_, e) => Expr::Neg(Box::new(e)),
                })
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Expr, ParseError> {
        let base = self.primary()?;
        if self.peek().kind != Kind::Caret {
            return Ok(base);
        }
        self.bump();
        self.descend()?;
        let exponent = self.unary()?;
        self.depth -= 1;
        Ok(Expr::Pow(Box::new(base), Box::new(exponent)))
    }

    fn primary(&mut self) -> Result<Expr, ParseError> {
        let prev_star = self.pos > 0 && self.tokens[self.pos - 1].kind == Kind::Star;
        let tok = self.bump();
        match tok.kind {
            Kind::Num(v) => Ok(Expr::Num(v)),
            Kind::LParen => {
                self.descend()?;
                let e = self.sum()?;
                self.depth -= 1;
                self.expect(Kind::RParen, "')'")?;
                Ok(e)
            }
            Kind::Name if self.peek().kind == Kind::LParen => self.call(&tok),
            Kind::Name | Kind::Quoted if self.peek().kind == Kind::Dot => self.signal(&tok),
            Kind::Quoted => {
                let next = self.peek();
                Err(next.error(format!(
                    "expected '.' and e, f, p or q after the element name '{}' but found {}",
                    tok.text,
                    next.describe()
                )))
            }
            Kind::Name => {
                if Func::from_name(&tok.text).is_some() {
                    let next = self.peek();
                    return Err(next.error(format!(
                        "expected '(' after function '{}' but found {}",
                        tok.text,
                        next.describe()
                    )));
                }
                Ok(match tok.text.as_str() {
                    "pi" => Expr::Num(PI),
                    "t" => Expr::Time,
                    "e" | "f" | "p" | "q" => Expr::Local(tok.text),
                    _ => Expr::Param(tok.text),
                })
            }
            _ => {
                let hint = if prev_star && tok.kind == Kind::Star {
                    " (write powers with '^')"
                } else {
                    ""
                };
                Err(tok.error(format!(
                    "expected an expression but found {}{hint}",
                    tok.describe()
                )))
            }
        }
    }

    /// `Element.x`: the variable `x` (e, f, p or q) of another element.
    fn signal(&mut self, element: &Token) -> Result<Expr, ParseError> {
        self.bump(); // '.'
        let tok = self.bump();
        match (tok.kind, tok.text.as_str()) {
            (Kind::Name, "e" | "f" | "p" | "q") => Ok(Expr::signal(&element.text, &tok.text)),
            _ => Err(tok.error(format!(
                "expected e, f, p or q after '{}.' but found {}",
                element.text,
                tok.describe()
            ))),
        }
    }

    fn call(&mut self, name: &Token) -> Result<Expr, ParseError> {
        let Some(func) = Func::from_name(&name.text) else {
            let known: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
            return Err(name.error(format!(
                "unknown function '{}' (expected one of {}, log)",
                name.text,
                known.join(", ")
            )));
        };
        self.bump(); // '('
        self.descend()?;
        let mut args = Vec::new();
        if self.peek().kind != Kind::RParen {
            loop {
                args.push(self.sum()?);
                let tok = self.bump();
                match tok.kind {
                    Kind::Comma => {}
                    Kind::RParen => break,
                    _ => {
                        return Err(
                            tok.error(format!("expected ',' or ')' but found {}", tok.describe()))
                        );
                    }
                }
            }
        } else {
            self.bump();
        }
        self.depth -= 1;
        if args.len() != func.arity() {
            let plural = if func.arity() == 1 { "" } else { "s" };
            return Err(name.error(format!(
                "expected function '{}' to take {} argument{plural} but found {}",
                name.text,
                func.arity(),
                args.len()
            )));
        }
        Ok(Expr::Call(func, args))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(src: &str) -> ParseError {
        parse(src).expect_err(src)
    }

    fn num(src: &str) -> f64 {
        parse(src).unwrap().eval(&|_| None).unwrap()
    }

    #[test]
    fn reads_number_forms() {
        assert_eq!(parse("42").unwrap(), Expr::Num(42.0));
        assert_eq!(parse("2.5").unwrap(), Expr::Num(2.5));
        assert_eq!(parse(".5").unwrap(), Expr::Num(0.5));
        assert_eq!(parse("1e-3").unwrap(), Expr::Num(1e-3));
        assert_eq!(parse("1.5E+2").unwrap(), Expr::Num(150.0));
        assert_eq!(parse("3.").unwrap(), Expr::Num(3.0));
    }

    #[test]
    fn classifies_names() {
        assert_eq!(parse("e").unwrap(), Expr::Local("e".into()));
        assert_eq!(parse("q").unwrap(), Expr::Local("q".into()));
        assert_eq!(parse("t").unwrap(), Expr::Time);
        assert_eq!(parse("pi").unwrap(), Expr::Num(PI));
        assert_eq!(parse("tau_c").unwrap(), Expr::param("tau_c"));
        assert_eq!(parse("e1").unwrap(), Expr::param("e1"));
    }

    #[test]
    fn power_binds_tighter_than_unary_minus() {
        let x = Expr::Local("f".into());
        let two = Expr::Num(2.0);
        assert_eq!(
            parse("-f^2").unwrap(),
            Expr::Neg(Box::new(Expr::Pow(Box::new(x), Box::new(two))))
        );
        assert_eq!(num("-2^2"), -4.0);
        assert_eq!(num("(-2)^2"), 4.0);
        assert_eq!(num("2^-1"), 0.5);
    }

    #[test]
    fn power_is_right_associative() {
        assert_eq!(num("2^3^2"), 512.0);
    }

    #[test]
    fn subtraction_and_division_are_left_associative() {
        assert_eq!(num("10 - 4 - 3"), 3.0);
        assert_eq!(num("24 / 4 / 3"), 2.0);
        assert_eq!(num("2 + 3 * 4"), 14.0);
        assert_eq!(num("-3 * 2 + 1"), -5.0);
    }

    #[test]
    fn sums_are_flat_in_written_order() {
        let e = parse("e1 - e2 - e4").unwrap();
        let Expr::Add(terms) = e else {
            panic!("not a sum")
        };
        assert_eq!(terms.len(), 3);
        assert!(matches!(terms[1], Expr::Neg(_)));
    }

    #[test]
    fn calls_check_names_and_arity() {
        assert_eq!(num("max(1, min(2, 3))"), 2.0);
        assert_eq!(num("log(1)"), 0.0);
        assert_eq!(num("atan2(0, 1)"), 0.0);
    }

    #[test]
    fn missing_paren_points_past_the_end() {
        let e = err("R * (f");
        assert_eq!(e.column, 7);
        assert_eq!(
            e.to_string(),
            "expected ')' but found end of input at column 7"
        );
    }

    #[test]
    fn double_star_points_at_second_star() {
        let e = err("R ** f");
        assert_eq!(e.column, 4);
        assert!(
            e.message
                .starts_with("expected an expression but found '*'")
        );
        assert!(e.message.contains("'^'"));
    }

    #[test]
    fn unknown_function_is_named() {
        let e = err("2 * foo(f)");
        assert_eq!(e.column, 5);
        assert!(e.message.starts_with("unknown function 'foo'"), "{e}");
    }

    #[test]
    fn wrong_arity_names_function_and_count() {
        let e = err("tanh(f, 2)");
        assert_eq!(e.column, 1);
        assert_eq!(
            e.message,
            "expected function 'tanh' to take 1 argument but found 2"
        );
        assert!(err("atan2(f)").message.contains("2 arguments"));
        assert!(err("sin()").message.contains("found 0"));
    }

    #[test]
    fn empty_input_is_rejected() {
        for src in ["", "   "] {
            let e = err(src);
            assert_eq!(e.message, "expected an expression but found end of input");
            assert_eq!(e.column, src.len() + 1);
        }
    }

    #[test]
    fn infinite_literal_is_rejected() {
        let e = err("2 * 1e999");
        assert_eq!(e.column, 5);
        assert_eq!(e.message, "expected a finite number but found '1e999'");
    }

    #[test]
    fn trailing_garbage_is_rejected() {
        let e = err("R f");
        assert_eq!(e.column, 3);
        assert_eq!(
            e.message,
            "expected an operator or end of input but found name 'f'"
        );
        assert_eq!(err("(R))").column, 4);
        assert_eq!(err("R $ f").column, 3);
        assert_eq!(err("2e").column, 3);
        assert_eq!(err("sin + 1").column, 5);
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        assert_eq!(err("ω").column, 1);
        assert_eq!(err("(ω)").column, 2);
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let src = "(".repeat(10_000) + "1" + &")".repeat(10_000);
        assert!(err(&src).message.contains("nesting"));
        let src = "-".repeat(10_000) + "1";
        assert!(err(&src).message.contains("nesting"));
        assert_eq!(num(&("(".repeat(50) + "1" + &")".repeat(50))), 1.0);
    }
}
