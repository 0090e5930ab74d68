//! Qualitative values: the sign of a deviation from nominal.

use std::fmt;
use std::ops::{Mul, Neg};

/// A qualitative deviation: below (`-`), at (`0`) or above (`+`) nominal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Qual {
    /// Below nominal.
    Minus,
    /// At nominal (within the band).
    Zero,
    /// Above nominal.
    Plus,
}

impl Qual {
    /// The sign of `x`, with values within `band` of zero counted as `0`.
    pub fn of(x: f64, band: f64) -> Qual {
        if x > band {
            Qual::Plus
        } else if x < -band {
            Qual::Minus
        } else {
            Qual::Zero
        }
    }

    /// `-1`, `0` or `1`.
    pub fn as_i8(self) -> i8 {
        match self {
            Qual::Minus => -1,
            Qual::Zero => 0,
            Qual::Plus => 1,
        }
    }

    /// Parses `+`, `-`, `0`.
    pub fn parse(s: &str) -> Option<Qual> {
        match s {
            "+" => Some(Qual::Plus),
            "-" => Some(Qual::Minus),
            "0" => Some(Qual::Zero),
            _ => None,
        }
    }
}

impl Neg for Qual {
    type Output = Qual;
    fn neg(self) -> Qual {
        match self {
            Qual::Minus => Qual::Plus,
            Qual::Zero => Qual::Zero,
            Qual::Plus => Qual::Minus,
        }
    }
}

impl Mul for Qual {
    type Output = Qual;
    fn mul(self, rhs: Qual) -> Qual {
        match self.as_i8() * rhs.as_i8() {
            1 => Qual::Plus,
            -1 => Qual::Minus,
            _ => Qual::Zero,
        }
    }
}

impl fmt::Display for Qual {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Qual::Minus => "-",
            Qual::Zero => "0",
            Qual::Plus => "+",
        })
    }
}
