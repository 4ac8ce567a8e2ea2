//! fuzzylite's `Function` term: an infix formula of the engine's inputs, outputs and `x`.
//!
//! The language is fuzzylite 6's: numbers; variable names (any input or output of the engine, and
//! `x`, the value the term is asked about); `+ - * / % ^` (`^` binds tightest and groups from the
//! right, `* / %` before `+ -`); unary `~` or `-` (negation) and `!` (logical not: 1 when the
//! operand is 0); `and` / `or` between 0/1 values, below every arithmetic operator; parentheses;
//! and the functions `abs fabs acos acosh asin asinh atan atanh ceil cos cosh exp floor log log10
//! log1p round sin sinh sqrt tan tanh` (one argument) and `atan2 fmod max min pow gt ge eq neq le
//! lt` (two, comparisons giving 1 or 0). A variable's value is its latest: an output not yet
//! defuzzified in this evaluation still holds the previous evaluation's value, as in fuzzylite.
//!
//! A formula is checked when it is read (unknown names, unbalanced parentheses, a missing operand,
//! nesting deeper than [`MAX_DEPTH`]) and evaluating it cannot fail: NaN propagates.

use std::fmt;

use super::FuzzyError;

/// The values a Takagi–Sugeno term reads: the engine's current inputs and outputs.
#[derive(Debug, Clone, Copy, Default)]
pub struct Values<'a> {
    /// Input values, in the engine's order.
    pub inputs: &'a [f64],
    /// Output values, in the engine's order (the latest defuzzified).
    pub outputs: &'a [f64],
}

/// How deeply parentheses and operators may nest: evaluation recurses, and a hostile file must
/// not overflow the stack.
pub const MAX_DEPTH: usize = 64;

/// The most numbers, names and symbols a formula may hold (a chain `1+1+…` nests one level per
/// operator in the tree that evaluation recurses over).
pub const MAX_TOKENS: usize = 1024;

/// What a name in a formula refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Var {
    /// The value the term is evaluated at.
    X,
    /// An input variable, by index.
    Input(usize),
    /// An output variable, by index.
    Output(usize),
}

#[derive(Debug, Clone, Copy)]
enum Unary {
    Negate,
    Not,
    Call(fn(f64) -> f64),
}

#[derive(Debug, Clone, Copy)]
enum Binary {
    Call(fn(f64, f64) -> f64),
}

#[derive(Debug, Clone)]
enum Node {
    Number(f64),
    Var(Var),
    Unary(Unary, Box<Node>),
    Binary(Binary, Box<Node>, Box<Node>),
}

/// A parsed formula and the text it was read from.
#[derive(Debug, Clone)]
pub struct Formula {
    text: String,
    root: Node,
}

/// Two formulas are equal when their texts are: the tree is read from the text.
impl PartialEq for Formula {
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

fn truth(b: bool) -> f64 {
    f64::from(u8::from(b))
}

fn unary_function(name: &str) -> Option<fn(f64) -> f64> {
    Some(match name {
        "abs" | "fabs" => f64::abs,
        "acos" => f64::acos,
        "acosh" => f64::acosh,
        "asin" => f64::asin,
        "asinh" => f64::asinh,
        "atan" => f64::atan,
        "atanh" => f64::atanh,
        "ceil" => f64::ceil,
        "cos" => f64::cos,
        "cosh" => f64::cosh,
        "exp" => f64::exp,
        "floor" => f64::floor,
        "log" => f64::ln,
        "log10" => f64::log10,
        "log1p" => f64::ln_1p,
        "round" => f64::round,
        "sin" => f64::sin,
        "sinh" => f64::sinh,
        "sqrt" => f64::sqrt,
        "tan" => f64::tan,
        "tanh" => f64::tanh,
        _ => return None,
    })
}

fn binary_function(name: &str) -> Option<fn(f64, f64) -> f64> {
    Some(match name {
        "atan2" => f64::atan2,
        "fmod" => |a: f64, b: f64| a % b,
        "max" => f64::max,
        "min" => f64::min,
        "pow" => f64::powf,
        "gt" => |a, b| truth(a > b),
        "ge" => |a, b| truth(a >= b),
        "eq" => |a, b| truth(a == b),
        "neq" => |a, b| truth(a != b),
        "le" => |a, b| truth(a <= b),
        "lt" => |a, b| truth(a < b),
        _ => return None,
    })
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Number(f64),
    Name(String),
    Symbol(char),
}

fn tokens(text: &str) -> Result<Vec<Token>, String> {
    let mut out = Vec::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while chars
                .get(i)
                .is_some_and(|c| c.is_ascii_digit() || *c == '.')
            {
                i += 1;
            }
            // An exponent: e or E, an optional sign, digits.
            if chars.get(i).is_some_and(|c| *c == 'e' || *c == 'E') {
                let mut j = i + 1;
                if chars.get(j).is_some_and(|c| *c == '+' || *c == '-') {
                    j += 1;
                }
                if chars.get(j).is_some_and(char::is_ascii_digit) {
                    i = j;
                    while chars.get(i).is_some_and(char::is_ascii_digit) {
                        i += 1;
                    }
                }
            }
            let word: String = chars[start..i].iter().collect();
            let value = word
                .parse::<f64>()
                .map_err(|_| format!("cannot read {word:?} as a number"))?;
            out.push(Token::Number(value));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while chars
                .get(i)
                .is_some_and(|c| c.is_alphanumeric() || *c == '_' || *c == '.')
            {
                i += 1;
            }
            out.push(Token::Name(chars[start..i].iter().collect()));
        } else if "+-*/%^~!(),".contains(c) {
            out.push(Token::Symbol(c));
            i += 1;
        } else {
            return Err(format!("unexpected character {c:?}"));
        }
    }
    Ok(out)
}

/// A recursive-descent reader over the tokens; `depth` bounds the nesting.
struct ExpressionReader<'a, F: Fn(&str) -> Option<Var>> {
    tokens: &'a [Token],
    at: usize,
    resolve: &'a F,
}

impl<F: Fn(&str) -> Option<Var>> ExpressionReader<'_, F> {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.at)
    }

    fn deeper(depth: usize) -> Result<usize, String> {
        if depth >= MAX_DEPTH {
            Err(format!("nested deeper than {MAX_DEPTH} levels"))
        } else {
            Ok(depth + 1)
        }
    }

    /// or < and < + - < * / % < unary < ^ < atoms.
    fn expression(&mut self, depth: usize) -> Result<Node, String> {
        let depth = Self::deeper(depth)?;
        let mut left = self.conjunction(depth)?;
        while matches!(self.peek(), Some(Token::Name(n)) if n == "or") {
            self.at += 1;
            let right = self.conjunction(depth)?;
            left = Node::Binary(
                Binary::Call(|a, b| truth(a == 1.0 || b == 1.0)),
                Box::new(left),
                Box::new(right),
            );
        }
        Ok(left)
    }

    fn conjunction(&mut self, depth: usize) -> Result<Node, String> {
        let mut left = self.sum(depth)?;
        while matches!(self.peek(), Some(Token::Name(n)) if n == "and") {
            self.at += 1;
            let right = self.sum(depth)?;
            left = Node::Binary(
                Binary::Call(|a, b| truth(a == 1.0 && b == 1.0)),
                Box::new(left),
                Box::new(right),
            );
        }
        Ok(left)
    }

    fn sum(&mut self, depth: usize) -> Result<Node, String> {
        let mut left = self.product(depth)?;
        while let Some(Token::Symbol(c @ ('+' | '-'))) = self.peek() {
            let f: fn(f64, f64) -> f64 = if *c == '+' {
                |a, b| a + b
            } else {
                |a, b| a - b
            };
            self.at += 1;
            let right = self.product(depth)?;
            left = Node::Binary(Binary::Call(f), Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn product(&mut self, depth: usize) -> Result<Node, String> {
        let mut left = self.unary(depth)?;
        while let Some(Token::Symbol(c @ ('*' | '/' | '%'))) = self.peek() {
            let f: fn(f64, f64) -> f64 = match c {
                '*' => |a, b| a * b,
                '/' => |a, b| a / b,
                _ => |a, b| a % b,
            };
            self.at += 1;
            let right = self.unary(depth)?;
            left = Node::Binary(Binary::Call(f), Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn unary(&mut self, depth: usize) -> Result<Node, String> {
        match self.peek() {
            Some(Token::Symbol(c @ ('~' | '-' | '!' | '+'))) => {
                let op = match c {
                    '!' => Some(Unary::Not),
                    '+' => None,
                    _ => Some(Unary::Negate),
                };
                self.at += 1;
                let depth = Self::deeper(depth)?;
                let operand = self.unary(depth)?;
                Ok(match op {
                    Some(op) => Node::Unary(op, Box::new(operand)),
                    None => operand,
                })
            }
            _ => self.power(depth),
        }
    }

    fn power(&mut self, depth: usize) -> Result<Node, String> {
        let base = self.atom(depth)?;
        if let Some(Token::Symbol('^')) = self.peek() {
            self.at += 1;
            let depth = Self::deeper(depth)?;
            // Right-associative: 2^3^2 = 2^9.
            let exponent = self.unary(depth)?;
            return Ok(Node::Binary(
                Binary::Call(f64::powf),
                Box::new(base),
                Box::new(exponent),
            ));
        }
        Ok(base)
    }

    fn expect(&mut self, symbol: char) -> Result<(), String> {
        match self.peek() {
            Some(Token::Symbol(c)) if *c == symbol => {
                self.at += 1;
                Ok(())
            }
            Some(t) => Err(format!("expected {symbol:?}, found {}", shown(t))),
            None => Err(format!("expected {symbol:?} at the end")),
        }
    }

    fn atom(&mut self, depth: usize) -> Result<Node, String> {
        let token = self
            .peek()
            .cloned()
            .ok_or_else(|| "a value is missing at the end".to_string())?;
        self.at += 1;
        match token {
            Token::Number(v) => Ok(Node::Number(v)),
            Token::Symbol('(') => {
                let inner = self.expression(depth)?;
                self.expect(')')?;
                Ok(inner)
            }
            Token::Name(name) => {
                if let Some(Token::Symbol('(')) = self.peek() {
                    self.at += 1;
                    let first = self.expression(depth)?;
                    if let Some(f) = unary_function(&name) {
                        self.expect(')')?;
                        return Ok(Node::Unary(Unary::Call(f), Box::new(first)));
                    }
                    if let Some(f) = binary_function(&name) {
                        self.expect(',')?;
                        let second = self.expression(depth)?;
                        self.expect(')')?;
                        return Ok(Node::Binary(
                            Binary::Call(f),
                            Box::new(first),
                            Box::new(second),
                        ));
                    }
                    return Err(format!("unknown function {name:?}"));
                }
                (self.resolve)(&name)
                    .map(Node::Var)
                    .ok_or_else(|| format!("unknown variable {name:?}"))
            }
            Token::Symbol(c) => Err(format!("unexpected {c:?}")),
        }
    }
}

fn shown(t: &Token) -> String {
    match t {
        Token::Number(v) => format!("{v}"),
        Token::Name(n) => format!("{n:?}"),
        Token::Symbol(c) => format!("{c:?}"),
    }
}

impl Formula {
    /// Reads `text`; `resolve` says what a name means (`x` is always [`Var::X`]).
    ///
    /// ```
    /// use cutlab::control::fuzzy::function::{Formula, Var};
    /// use cutlab::control::fuzzy::membership::Values;
    /// let f = Formula::parse("sin(a)/a + 2^3^0 * -x", |n| (n == "a").then_some(Var::Input(0)))
    ///     .unwrap();
    /// let v = f.evaluate(0.5, Values { inputs: &[1.0], outputs: &[] });
    /// assert!((v - (1f64.sin() - 2.0 * 0.5)).abs() < 1e-15);
    /// assert!(Formula::parse("sin(b", |_| None).is_err());
    /// ```
    pub fn parse(text: &str, resolve: impl Fn(&str) -> Option<Var>) -> Result<Formula, FuzzyError> {
        let fail = |m: String| FuzzyError::new(format!("formula {:?}: {m}", text.trim()));
        let tokens = tokens(text).map_err(fail)?;
        // Evaluation and dropping recurse over the tree: a formula this long is no formula.
        if tokens.len() > MAX_TOKENS {
            return Err(fail(format!("longer than {MAX_TOKENS} tokens")));
        }
        if tokens.is_empty() {
            return Err(FuzzyError::new("a Function term needs a formula"));
        }
        let lookup = |name: &str| {
            if name == "x" {
                Some(Var::X)
            } else {
                resolve(name)
            }
        };
        let mut reader = ExpressionReader {
            tokens: &tokens,
            at: 0,
            resolve: &lookup,
        };
        let root = reader.expression(0).map_err(fail)?;
        if let Some(t) = reader.peek() {
            return Err(fail(format!("unexpected {} after the formula", shown(t))));
        }
        Ok(Formula {
            text: text.split_whitespace().collect::<Vec<_>>().join(" "),
            root,
        })
    }

    /// The formula as read (whitespace collapsed).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The formula's value at `x` with the engine's current `values` (NaN for a variable the
    /// values do not hold).
    pub fn evaluate(&self, x: f64, values: Values<'_>) -> f64 {
        eval(&self.root, x, values)
    }
}

fn eval(node: &Node, x: f64, values: Values<'_>) -> f64 {
    match node {
        Node::Number(v) => *v,
        Node::Var(Var::X) => x,
        Node::Var(Var::Input(i)) => values.inputs.get(*i).copied().unwrap_or(f64::NAN),
        Node::Var(Var::Output(i)) => values.outputs.get(*i).copied().unwrap_or(f64::NAN),
        Node::Unary(op, a) => {
            let a = eval(a, x, values);
            match op {
                Unary::Negate => -a,
                Unary::Not => truth(a == 0.0),
                Unary::Call(f) => f(a),
            }
        }
        Node::Binary(Binary::Call(f), a, b) => f(eval(a, x, values), eval(b, x, values)),
    }
}

impl fmt::Display for Formula {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(text: &str, x: f64) -> f64 {
        Formula::parse(text, |_| None)
            .unwrap()
            .evaluate(x, Values::default())
    }

    #[test]
    fn precedence_and_associativity_follow_fuzzylite() {
        assert_eq!(value("1 + 2 * 3", 0.0), 7.0);
        assert_eq!(value("2 ^ 3 ^ 2", 0.0), 512.0);
        assert_eq!(value("-2 ^ 2", 0.0), -4.0);
        assert_eq!(value("(1 + 2) * 3 % 4", 0.0), 1.0);
        assert_eq!(value("max(x, 3) - min(1, x)", 5.0), 4.0);
        assert_eq!(value("gt(x, 1) and lt(x, 3)", 2.0), 1.0);
        assert_eq!(value("1.5e1 / ~3", 0.0), -5.0);
        assert!(value("sqrt(-1)", 0.0).is_nan());
    }

    #[test]
    fn broken_formulas_are_refused_saying_what_is_wrong_never_panic() {
        for (text, message) in [
            ("sin(x", "expected ')'"),
            ("1 +", "a value is missing"),
            ("foo(x)", "unknown function \"foo\""),
            ("y + 1", "unknown variable \"y\""),
            ("1 2", "unexpected 2"),
            ("1 $ 2", "unexpected character '$'"),
            ("atan2(1)", "expected ','"),
        ] {
            let e = Formula::parse(text, |_| None).unwrap_err().to_string();
            assert!(e.contains(message), "{text}: {e}");
        }
        let deep = format!("{}1{}", "(".repeat(100), ")".repeat(100));
        let e = Formula::parse(&deep, |_| None).unwrap_err().to_string();
        assert!(e.contains("nested deeper than 64"), "{e}");
        let long = format!("{}1", "1+".repeat(10_000));
        let e = Formula::parse(&long, |_| None).unwrap_err().to_string();
        assert!(e.contains("longer than 1024 tokens"), "{e}");
        let negations = format!("{}1", "-".repeat(10_000));
        assert!(Formula::parse(&negations, |_| None).is_err());
    }
}
