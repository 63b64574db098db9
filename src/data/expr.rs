//! Linear expressions in `x` for `--map NAME=EXPR` (`90-x`, `2*x+1`, `-x`, `x/2`, `0.5*x-3`,
//! parentheses allowed): parsed by recursive descent into `a·x + b`, so anything non-linear
//! (`x*x`, `1/x`) is an error at parse time rather than a surprise at load time.

use std::fmt;

/// The map `x ↦ a·x + b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linear {
    pub a: f64,
    pub b: f64,
}

impl Linear {
    /// The identity map.
    pub const IDENTITY: Linear = Linear { a: 1.0, b: 0.0 };

    /// Apply the map.
    pub fn apply(&self, x: f64) -> f64 {
        self.a * x + self.b
    }

    /// Parse a linear expression in `x`; the error gives the 1-based character position.
    pub fn parse(text: &str) -> Result<Linear, String> {
        let mut p = Parser {
            chars: text.chars().collect(),
            pos: 0,
            depth: 0,
        };
        let value = p.expr()?;
        p.skip_spaces();
        if p.pos < p.chars.len() {
            return Err(p.error("expected `+`, `-`, `*`, `/` or the end"));
        }
        if !(value.a.is_finite() && value.b.is_finite()) {
            return Err("the expression does not give a finite map".into());
        }
        Ok(value)
    }
}

impl fmt::Display for Linear {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}*x + {}", self.a, self.b)
    }
}

/// Recursive-descent parser over the characters of an expression.
struct Parser {
    chars: Vec<char>,
    pos: usize,
    /// Nesting of `factor` calls (parentheses and signs), bounded by [`MAX_DEPTH`].
    depth: usize,
}

/// Deepest nesting of parentheses and signs: far beyond any real map, far below what overflows
/// the stack (60k parentheses or 100k minus signs aborted the process).
const MAX_DEPTH: usize = 200;

impl Parser {
    fn error(&self, what: &str) -> String {
        let found = self
            .chars
            .get(self.pos)
            .map_or("the end".to_string(), |c| format!("`{c}`"));
        format!(
            "at character {}: {what}, found {found} (write a linear expression in x such as \
             `90-x`, `2*x+1`, `x/2`)",
            self.pos + 1
        )
    }

    fn skip_spaces(&mut self) {
        while self.chars.get(self.pos).is_some_and(|c| c.is_whitespace()) {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_spaces();
        self.chars.get(self.pos).copied()
    }

    /// expr := term (('+' | '-') term)*
    fn expr(&mut self) -> Result<Linear, String> {
        let mut acc = self.term()?;
        while let Some(op @ ('+' | '-')) = self.peek() {
            self.pos += 1;
            let rhs = self.term()?;
            let s = if op == '+' { 1.0 } else { -1.0 };
            acc = Linear {
                a: acc.a + s * rhs.a,
                b: acc.b + s * rhs.b,
            };
        }
        Ok(acc)
    }

    /// term := factor (('*' | '/') factor)*
    fn term(&mut self) -> Result<Linear, String> {
        let mut acc = self.factor()?;
        while let Some(op @ ('*' | '/')) = self.peek() {
            let at = self.pos;
            self.pos += 1;
            let rhs = self.factor()?;
            acc = if op == '*' {
                if acc.a != 0.0 && rhs.a != 0.0 {
                    self.pos = at;
                    return Err(self.error("x times x is not linear"));
                }
                Linear {
                    a: acc.a * rhs.b + acc.b * rhs.a,
                    b: acc.b * rhs.b,
                }
            } else {
                if rhs.a != 0.0 {
                    self.pos = at;
                    return Err(self.error("dividing by x is not linear"));
                }
                if rhs.b == 0.0 {
                    self.pos = at;
                    return Err(self.error("division by zero"));
                }
                Linear {
                    a: acc.a / rhs.b,
                    b: acc.b / rhs.b,
                }
            };
        }
        Ok(acc)
    }

    /// factor := ('+' | '-') factor | 'x' | number | '(' expr ')'
    fn factor(&mut self) -> Result<Linear, String> {
        if self.depth >= MAX_DEPTH {
            return Err(self.error(&format!(
                "more than {MAX_DEPTH} nested parentheses or signs"
            )));
        }
        self.depth += 1;
        let f = self.factor_inner();
        self.depth -= 1;
        f
    }

    fn factor_inner(&mut self) -> Result<Linear, String> {
        match self.peek() {
            Some('-') => {
                self.pos += 1;
                let f = self.factor()?;
                Ok(Linear { a: -f.a, b: -f.b })
            }
            Some('+') => {
                self.pos += 1;
                self.factor()
            }
            Some('x' | 'X') => {
                self.pos += 1;
                Ok(Linear::IDENTITY)
            }
            Some('(') => {
                self.pos += 1;
                let e = self.expr()?;
                if self.peek() != Some(')') {
                    return Err(self.error("expected `)`"));
                }
                self.pos += 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(),
            _ => Err(self.error("expected a number, `x` or `(`")),
        }
    }

    /// A decimal number with optional fraction and exponent.
    fn number(&mut self) -> Result<Linear, String> {
        let start = self.pos;
        let digits = |p: &mut Parser| {
            while p.chars.get(p.pos).is_some_and(|c| c.is_ascii_digit()) {
                p.pos += 1;
            }
        };
        digits(self);
        if self.chars.get(self.pos) == Some(&'.') {
            self.pos += 1;
            digits(self);
        }
        if matches!(self.chars.get(self.pos), Some('e' | 'E')) {
            let save = self.pos;
            self.pos += 1;
            if matches!(self.chars.get(self.pos), Some('+' | '-')) {
                self.pos += 1;
            }
            let before = self.pos;
            digits(self);
            if self.pos == before {
                self.pos = save;
            }
        }
        let text: String = self.chars[start..self.pos].iter().collect();
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Linear { a: 0.0, b: v }),
            _ => {
                self.pos = start;
                Err(self.error("expected a finite number"))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_forms() {
        let cases = [
            ("90-x", -1.0, 90.0),
            ("2*x+1", 2.0, 1.0),
            ("-x", -1.0, 0.0),
            ("x/2", 0.5, 0.0),
            ("0.5*x-3", 0.5, -3.0),
            (" ( x + 10 ) * 2 ", 2.0, 20.0),
            ("x", 1.0, 0.0),
            ("1e1 - x", -1.0, 10.0),
        ];
        for (text, a, b) in cases {
            // Every coefficient here is exact in binary, so equality is the right test.
            assert_eq!(Linear::parse(text), Ok(Linear { a, b }), "{text}");
        }
    }

    #[test]
    fn rejects_non_linear_and_garbage_with_a_position() {
        for (text, pos) in [
            ("x*x", 2),
            ("1/x", 2),
            ("x/0", 2),
            ("90-", 4),
            ("2x", 2),
            ("y", 1),
            ("", 1),
        ] {
            let err = Linear::parse(text).unwrap_err();
            assert!(
                err.contains(&format!("at character {pos}")),
                "{text}: {err}"
            );
        }
    }
}
