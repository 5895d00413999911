//! The parser of the expression language: text in, [`ExprId`] out, errors with byte spans.
//!
//! Enter with [`Pool::parse`] or, to check names and set limits, [`Pool::parse_with`]
//! and [`ParseOptions`]. The parser is hand-written recursive descent over a
//! one-token lookahead lexer; every recursion (parentheses, function calls, unary
//! signs, exponents) goes through one depth counter bounded by
//! [`Limits::max_depth`], so no input can overflow the stack.
//!
//! Grammar, loosest binding first:
//!
//! ```text
//! sum      = product (('+' | '-') product)*
//! product  = ('-' | '+')* power (('*' | '/') unary)*   a leading sign negates the whole product
//! unary    = ('-' | '+') unary | power
//! power    = atom (('^' | '**') exponent)?          right-associative
//! exponent = ('-' | '+') exponent | power            so 2^-1 and x^-y^2 read naturally
//! atom     = number | name '\''{0,2} | 'pi' | function '(' sum (',' sum)* ')' | '(' sum ')'
//! ```
//!
//! An integer literal is an exact [`Rational`](crate::Rational); one that does not
//! fit in `i128` is [`ParseErrorKind::NumberOutOfRange`] rather than a silently
//! rounded float. A literal with `.` or an exponent is a float. `1/2` is exact
//! because the constructors fold it. Implicit multiplication (`2x`) is an error.
//! On error the pool may keep nodes built before the error; they are harmless.

use crate::expr::{ExprId, Func, Node, Pool};
use crate::number::{Number, Rational};

/// A byte range `start..end` in the parsed text.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Span {
    /// The first byte.
    pub start: u32,
    /// One past the last byte.
    pub end: u32,
}

impl Span {
    /// The span `start..end`, saturated to `u32`.
    pub fn new(start: usize, end: usize) -> Span {
        let clamp = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        Span { start: clamp(start), end: clamp(end) }
    }

    /// The range, for slicing the text.
    pub fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }
}

/// A parse error: what went wrong and where.
#[derive(Clone, PartialEq, Eq, Debug, thiserror::Error)]
#[error("{kind}")]
pub struct ParseError {
    /// What went wrong.
    pub kind: ParseErrorKind,
    /// Where, in bytes of the parsed text.
    pub span: Span,
}

impl ParseError {
    /// A hint for a common slip, given the parsed `text`: a product written
    /// without its `*` (`2x`, `2(x+1)`, `x y`), which the language never implies.
    pub fn hint(&self, text: &str) -> Option<String> {
        let ParseErrorKind::Expected { what, .. } = &self.kind else { return None };
        if !what.starts_with("an operator") {
            return None;
        }
        let range = self.span.range();
        let before = text.get(..range.start)?.trim_end();
        let found = text.get(range)?;
        let starts_operand = found.starts_with(|c: char| c.is_alphanumeric() || c == '_' || c == '(');
        let ends_operand = before.ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ')' || c == '\'');
        if !(starts_operand && ends_operand) {
            return None;
        }
        let word = |chars: &mut dyn Iterator<Item = char>| -> String {
            chars.take_while(|c| c.is_alphanumeric() || matches!(c, '_' | '.' | '\'')).collect()
        };
        let left = if before.ends_with(')') {
            "(...)".to_string()
        } else {
            word(&mut before.chars().rev()).chars().rev().collect()
        };
        let right = if found.starts_with('(') { "(...)".to_string() } else { word(&mut found.chars()) };
        Some(format!("a product needs its '*': write {left}*{right}"))
    }
}

/// What went wrong in a parse.
#[derive(Clone, PartialEq, Eq, Debug, thiserror::Error)]
pub enum ParseErrorKind {
    /// Something else stood where `what` was required.
    #[error("expected {what}, found {found}")]
    Expected {
        /// What the grammar needed here, e.g. "an expression after '+'".
        what: &'static str,
        /// What was there instead, e.g. "end of input" or "'x'".
        found: String,
    },
    /// A character that no token starts with.
    #[error("unexpected character '{ch}'")]
    UnexpectedChar {
        /// The character.
        ch: char,
    },
    /// A symbol the caller's `known` check rejected.
    #[error("unknown name '{name}'")]
    UnknownName {
        /// The name with its primes, e.g. `q'`.
        name: String,
    },
    /// A name followed by `(` that is not a function of the language.
    #[error("unknown function '{name}'")]
    UnknownFunction {
        /// The name.
        name: String,
    },
    /// A function called with the wrong number of arguments.
    #[error("function '{name}' takes {expected} argument{}, found {found}", if *expected == 1 { "" } else { "s" })]
    WrongArgCount {
        /// The function name as written.
        name: &'static str,
        /// The number it takes.
        expected: usize,
        /// The number given.
        found: usize,
    },
    /// A function name not followed by `(`.
    #[error("function '{name}' needs its argument in parentheses, as in {name}(x)")]
    MissingCall {
        /// The function name as written.
        name: &'static str,
    },
    /// More than two primes (`q'''`): only velocities and accelerations exist.
    #[error("at most two primes are allowed (q' is a velocity, q'' an acceleration)")]
    TooManyPrimes,
    /// Primes after the constant `pi`.
    #[error("'pi' is a constant and has no time derivative")]
    PrimedConstant,
    /// A `(` without its `)`.
    #[error("unclosed parenthesis")]
    UnclosedParen,
    /// A `)` without its `(`.
    #[error("unexpected ')'")]
    UnmatchedParen,
    /// An integer that does not fit in `i128`, or a float that overflows `f64`.
    #[error("number out of range")]
    NumberOutOfRange,
    /// Nesting deeper than [`Limits::max_depth`].
    #[error("nesting deeper than {limit} levels")]
    TooDeep {
        /// The limit.
        limit: usize,
    },
    /// Text longer than [`Limits::max_len`].
    #[error("expression longer than {limit} bytes")]
    TooLong {
        /// The limit.
        limit: usize,
    },
    /// A numeric exponent larger in magnitude than [`Limits::max_exponent`].
    #[error("exponent {value} is larger than {limit} in magnitude")]
    ExponentTooLarge {
        /// The exponent as written.
        value: String,
        /// The limit.
        limit: u64,
    },
    /// A floating-point constant (or a product of them) that is not finite.
    #[error("the constant overflows a 64-bit float")]
    NonFiniteConstant,
    /// A division by an expression that is exactly zero (`1/0`, `x/(x - x)`).
    #[error("division by zero")]
    DivisionByZero,
    /// A constant that has no value (`log(0)`, `sqrt(-1)`, `asin(2)`): it is an
    /// error where it is written, so that no simplification can drop it (`0*log(0)`).
    #[error("{text} has no finite value (it evaluates to {value})")]
    Undefined {
        /// The constant as written.
        text: String,
        /// What it evaluates to (`NaN`, `-inf`).
        value: String,
    },
    /// A power of zero with an exponent that is not a number (`0^x`): it is 0 or
    /// has no value by the exponent's sign, and its derivative holds `log(0)`.
    #[error("{text} is a power of zero with a variable exponent: 0 or no value by the exponent's sign")]
    ZeroToVariablePower {
        /// The power as written.
        text: String,
    },
    /// The parse would add more than [`Limits::max_nodes`] nodes to the pool.
    #[error("expression has more than {limit} nodes")]
    TooManyNodes {
        /// The limit.
        limit: usize,
    },
}

/// Bounds on what one parse may cost. They keep hostile or mistaken input
/// (a pasted file, 10 000 parentheses) from exhausting memory or the stack.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Limits {
    /// Longest accepted text in bytes. Default 100 000: a hundred times the
    /// longest expression of the lecture notes lagrange follows.
    pub max_len: usize,
    /// Deepest nesting of parentheses, function calls, unary signs and
    /// exponents. Default 64: hand-written expressions rarely nest past 10, and 64
    /// levels of recursion fit easily on any thread's stack.
    pub max_depth: usize,
    /// Most nodes one parse may add to the pool. Default 1 000 000, a guard
    /// against canonicalization blow-ups rather than a limit users should meet.
    pub max_nodes: usize,
    /// Largest magnitude of a numeric exponent. Default 1000: the steepest
    /// power laws in use (r^-12, r^-18) are far
    /// below it, while x^1000000000 would only produce meaningless numbers
    /// (and 2^1000000000 an unbounded exact integer). `u64::MAX` means no
    /// limit at all, so that any exponent the pool holds (`x^1e300`) reads back.
    pub max_exponent: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits { max_len: 100_000, max_depth: 64, max_nodes: 1_000_000, max_exponent: 1000 }
    }
}

/// How to parse: which symbols exist, and the [`Limits`].
#[derive(Clone, Copy, Default)]
pub struct ParseOptions<'a> {
    /// When set, every symbol (base name, number of primes) must pass this
    /// check, or the parse fails with [`ParseErrorKind::UnknownName`]. `pi` and
    /// function names are not symbols and are never checked; `t` is a symbol.
    // The signature says what the check receives; an alias would hide it.
    #[allow(clippy::type_complexity)]
    pub known: Option<&'a dyn Fn(&str, u8) -> bool>,
    /// Bounds on the parse.
    pub limits: Limits,
}

impl std::fmt::Debug for ParseOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParseOptions")
            .field("known", &self.known.map(|_| "Fn(&str, u8) -> bool"))
            .field("limits", &self.limits)
            .finish()
    }
}

impl<'a> ParseOptions<'a> {
    /// Accept only symbols for which `known(name, primes)` holds.
    pub fn with_known(mut self, known: &'a dyn Fn(&str, u8) -> bool) -> Self {
        self.known = Some(known);
        self
    }

    /// Use these limits.
    pub fn with_limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }
}

impl Pool {
    /// Parses `text` with default options (any name is a symbol).
    pub fn parse(&mut self, text: &str) -> Result<ExprId, ParseError> {
        self.parse_with(text, &ParseOptions::default())
    }

    /// Parses `text`, checking names and limits as `opts` says.
    pub fn parse_with(&mut self, text: &str, opts: &ParseOptions) -> Result<ExprId, ParseError> {
        if text.len() > opts.limits.max_len {
            let kind = ParseErrorKind::TooLong { limit: opts.limits.max_len };
            return Err(ParseError { kind, span: Span::new(opts.limits.max_len, text.len()) });
        }
        let start_len = self.len();
        let mut p = Parser { pool: self, text, opts, pos: 0, tok: Token::START, prev: Tok::End, depth: 0, start_len };
        p.bump()?;
        let e = p.sum()?;
        match p.tok.kind {
            Tok::End => Ok(e),
            Tok::RParen => Err(p.error(ParseErrorKind::UnmatchedParen, p.tok.span())),
            _ => Err(p.expected("an operator")),
        }
    }
}

/// The kinds of tokens.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Tok {
    Num,
    /// A name; `name_end` is where the primes start.
    Ident {
        name_end: usize,
    },
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    Comma,
    End,
}

#[derive(Clone, Copy, Debug)]
struct Token {
    kind: Tok,
    start: usize,
    end: usize,
}

impl Token {
    const START: Token = Token { kind: Tok::End, start: 0, end: 0 };

    fn span(self) -> Span {
        Span::new(self.start, self.end)
    }
}

/// The functions callable by name: the unary ones, `sqrt`, `atan2`, `ln`.
#[derive(Clone, Copy)]
enum Callee {
    Unary(Func),
    Sqrt,
    Atan2,
}

impl Callee {
    fn from_name(name: &str) -> Option<(Callee, &'static str)> {
        match name {
            "sqrt" => Some((Callee::Sqrt, "sqrt")),
            "atan2" => Some((Callee::Atan2, "atan2")),
            "ln" => Some((Callee::Unary(Func::Log), "ln")),
            _ => Func::from_name(name).map(|f| (Callee::Unary(f), f.name())),
        }
    }

    fn arity(self) -> usize {
        match self {
            Callee::Atan2 => 2,
            Callee::Unary(_) | Callee::Sqrt => 1,
        }
    }
}

struct Parser<'p, 't, 'o> {
    pool: &'p mut Pool,
    text: &'t str,
    opts: &'o ParseOptions<'o>,
    /// Where the lexer continues.
    pos: usize,
    /// The lookahead token.
    tok: Token,
    /// The kind of the token consumed last, for "expected ... after '+'".
    prev: Tok,
    depth: usize,
    start_len: usize,
}

type PResult<T> = Result<T, ParseError>;

impl Parser<'_, '_, '_> {
    // ---- errors ---------------------------------------------------------------

    fn error(&self, kind: ParseErrorKind, span: Span) -> ParseError {
        ParseError { kind, span }
    }

    /// "expected `what`, found <the lookahead>" at the lookahead.
    fn expected(&self, what: &'static str) -> ParseError {
        let found = match self.tok.kind {
            Tok::End => "end of input".to_string(),
            _ => {
                let s = &self.text[self.tok.start..self.tok.end];
                match s.char_indices().nth(24) {
                    Some((cut, _)) => format!("'{}...'", &s[..cut]),
                    None => format!("'{s}'"),
                }
            }
        };
        self.error(ParseErrorKind::Expected { what, found }, self.tok.span())
    }

    /// Enters one nesting level, or fails at the lookahead.
    fn enter(&mut self) -> PResult<()> {
        if self.depth >= self.opts.limits.max_depth {
            let kind = ParseErrorKind::TooDeep { limit: self.opts.limits.max_depth };
            return Err(self.error(kind, self.tok.span()));
        }
        self.depth += 1;
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    /// Fails when the parse has grown the pool past the node limit.
    fn check_nodes(&self, e: ExprId, span: Span) -> PResult<ExprId> {
        // The canonical form may hold nodes the text never wrote, one level
        // down: asin(-2) is -asin(2), and a product folds its numeric factors
        // into one (1e300*x*1e300 is inf*x). They are checked with `e`.
        let node = self.pool.node(e);
        let parts = || std::iter::once(e).chain(self.pool.children(node));
        if parts().any(|id| self.pool.as_number(id).is_some_and(|n| !n.to_f64().is_finite())) {
            return Err(self.error(ParseErrorKind::NonFiniteConstant, span));
        }
        let limit = self.opts.limits.max_nodes;
        if self.pool.len().saturating_sub(self.start_len) > limit {
            return Err(self.error(ParseErrorKind::TooManyNodes { limit }, span));
        }
        // A constant function value or power that has no value (log(0),
        // sqrt(-1), 0^-1) is an error here, before a product with zero or a
        // cancellation could make it vanish.
        let zero_power = |id: ExprId| match self.pool.node(id) {
            Node::Pow(b, x) => self.pool.is_zero(*b) && self.pool.as_number(*x).is_none(),
            _ => false,
        };
        if parts().any(zero_power) {
            let text = self.text[span.start as usize..span.end as usize].trim().to_string();
            return Err(self.error(ParseErrorKind::ZeroToVariablePower { text }, span));
        }
        if let Some(value) = parts().find_map(|id| self.pool.undefined_value(id)) {
            let text = self.text[span.start as usize..span.end as usize].trim().to_string();
            return Err(self.error(ParseErrorKind::Undefined { text, value: value.to_string() }, span));
        }
        // Folding can make an exponent the text never wrote: (x^999)^999 is
        // x^998001, x^999*x^999 is x^1998. The limit holds for those too, so
        // that every expression read prints as text that reads back.
        if let Some(value) = self.folded_exponent_over_limit(e) {
            let limit = self.opts.limits.max_exponent;
            return Err(self.error(ParseErrorKind::ExponentTooLarge { value, limit }, span));
        }
        Ok(e)
    }

    /// The exponent of `e` (a power, or a power among the factors of a product)
    /// that is a number beyond [`Limits::max_exponent`], if any.
    fn folded_exponent_over_limit(&self, e: ExprId) -> Option<String> {
        let limit = self.opts.limits.max_exponent;
        if limit == u64::MAX {
            return None;
        }
        let over = |id: ExprId| match self.pool.node(id) {
            Node::Pow(_, ex) => {
                self.pool.as_number(*ex).filter(|n| n.to_f64().abs() > limit as f64).map(|n| n.to_string())
            }
            _ => None,
        };
        match self.pool.node(e) {
            Node::Mul(fs) => fs.iter().find_map(|&f| over(f)),
            _ => over(e),
        }
    }

    // ---- lexer ------------------------------------------------------------------

    /// Consumes the lookahead and lexes the next token.
    fn bump(&mut self) -> PResult<()> {
        self.prev = self.tok.kind;
        let bytes = self.text.as_bytes();
        while let Some(c) = self.text[self.pos..].chars().next() {
            if !c.is_whitespace() {
                break;
            }
            self.pos += c.len_utf8();
        }
        let start = self.pos;
        let Some(&b) = bytes.get(start) else {
            self.tok = Token { kind: Tok::End, start, end: start };
            return Ok(());
        };
        let single = |kind| (kind, start + 1);
        let (kind, end) = match b {
            b'+' => single(Tok::Plus),
            b'-' => single(Tok::Minus),
            b'*' if bytes.get(start + 1) == Some(&b'*') => (Tok::Caret, start + 2),
            b'*' => single(Tok::Star),
            b'/' => single(Tok::Slash),
            b'^' => single(Tok::Caret),
            b'(' => single(Tok::LParen),
            b')' => single(Tok::RParen),
            b',' => single(Tok::Comma),
            b'0'..=b'9' | b'.' => (Tok::Num, self.number_end(start)),
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                let mut name_end = start + 1;
                while bytes.get(name_end).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') {
                    name_end += 1;
                }
                let mut end = name_end;
                while bytes.get(end) == Some(&b'\'') {
                    end += 1;
                }
                if end - name_end > 2 {
                    return Err(self.error(ParseErrorKind::TooManyPrimes, Span::new(start, end)));
                }
                (Tok::Ident { name_end }, end)
            }
            _ => {
                let ch = self.text[start..].chars().next().unwrap_or('\u{fffd}');
                let span = Span::new(start, start + ch.len_utf8());
                return Err(self.error(ParseErrorKind::UnexpectedChar { ch }, span));
            }
        };
        self.tok = Token { kind, start, end };
        self.pos = end;
        Ok(())
    }

    /// The end of the number literal starting at `start`: digits, an optional
    /// fraction, an optional exponent (only when digits follow the `e`).
    fn number_end(&self, start: usize) -> usize {
        let bytes = self.text.as_bytes();
        let digits = |mut i: usize| {
            while bytes.get(i).is_some_and(u8::is_ascii_digit) {
                i += 1;
            }
            i
        };
        let mut end = digits(start);
        if bytes.get(end) == Some(&b'.') {
            end = digits(end + 1);
        }
        if matches!(bytes.get(end), Some(b'e' | b'E')) {
            let mut exp = end + 1;
            if matches!(bytes.get(exp), Some(b'+' | b'-')) {
                exp += 1;
            }
            if bytes.get(exp).is_some_and(u8::is_ascii_digit) {
                end = digits(exp);
            }
        }
        end
    }

    // ---- grammar -------------------------------------------------------------------

    fn sum(&mut self) -> PResult<ExprId> {
        let start = self.tok.start;
        let first = self.product()?;
        let mut terms = vec![first];
        loop {
            let negate = match self.tok.kind {
                Tok::Plus => false,
                Tok::Minus => true,
                _ => break,
            };
            self.bump()?;
            let t = self.product()?;
            terms.push(if negate { self.pool.neg(t) } else { t });
        }
        if terms.len() == 1 {
            return Ok(first);
        }
        let e = self.pool.add(&terms);
        self.check_nodes(e, Span::new(start, self.tok.start))
    }

    /// A product. Its leading signs apply to the whole product, which is built
    /// in one call: `-(x + y)/x` is `mul(-1, x + y, 1/x)`, the form the printer
    /// writes that way (a number times a lone sum would distribute first).
    fn product(&mut self) -> PResult<ExprId> {
        let start = self.tok.start;
        let mut negative = false;
        let mut levels = 0;
        while let Tok::Minus | Tok::Plus = self.tok.kind {
            self.enter()?;
            levels += 1;
            negative ^= self.tok.kind == Tok::Minus;
            self.bump()?;
        }
        let first = self.power()?;
        let mut factors = vec![first];
        loop {
            let divide = match self.tok.kind {
                Tok::Star => false,
                Tok::Slash => true,
                _ => break,
            };
            self.bump()?;
            let f_start = self.tok.start;
            let f = self.unary()?;
            if divide && self.pool.is_zero(f) {
                return Err(self.error(ParseErrorKind::DivisionByZero, Span::new(f_start, self.tok.start)));
            }
            factors.push(if divide {
                let m1 = self.pool.minus_one();
                self.pool.pow(f, m1)
            } else {
                f
            });
        }
        self.depth -= levels;
        if negative {
            factors.insert(0, self.pool.minus_one());
        }
        if factors.len() == 1 {
            return Ok(first);
        }
        let e = self.pool.mul(&factors);
        self.check_nodes(e, Span::new(start, self.tok.start))
    }

    fn unary(&mut self) -> PResult<ExprId> {
        self.signed(Self::power)
    }

    fn exponent(&mut self) -> PResult<ExprId> {
        self.signed(Self::power)
    }

    /// Leading signs, then `operand`.
    fn signed(&mut self, operand: fn(&mut Self) -> PResult<ExprId>) -> PResult<ExprId> {
        let negate = match self.tok.kind {
            Tok::Minus => true,
            Tok::Plus => false,
            _ => return operand(self),
        };
        let start = self.tok.start;
        self.enter()?;
        self.bump()?;
        let e = self.signed(operand)?;
        self.leave();
        if !negate {
            return Ok(e);
        }
        let e = self.pool.neg(e);
        self.check_nodes(e, Span::new(start, self.tok.start))
    }

    fn power(&mut self) -> PResult<ExprId> {
        let start = self.tok.start;
        let base = self.atom()?;
        if self.tok.kind != Tok::Caret {
            return Ok(base);
        }
        self.enter()?;
        self.bump()?;
        let exp_start = self.tok.start;
        let exp = self.exponent()?;
        self.leave();
        if let Some(n) = self.pool.as_number(exp) {
            let limit = self.opts.limits.max_exponent;
            if limit != u64::MAX && n.to_f64().abs() > limit as f64 {
                let span = Span::new(exp_start, self.tok.start);
                return Err(self.error(ParseErrorKind::ExponentTooLarge { value: n.to_string(), limit }, span));
            }
        }
        let e = self.pool.pow(base, exp);
        self.check_nodes(e, Span::new(start, self.tok.start))
    }

    fn atom(&mut self) -> PResult<ExprId> {
        let tok = self.tok;
        match tok.kind {
            Tok::Num => {
                let e = self.number(tok)?;
                self.bump()?;
                self.check_nodes(e, tok.span())
            }
            Tok::Ident { name_end } => self.name(tok, name_end),
            Tok::LParen => {
                self.enter()?;
                self.bump()?;
                let e = self.sum()?;
                match self.tok.kind {
                    Tok::RParen => self.bump()?,
                    Tok::End => return Err(self.error(ParseErrorKind::UnclosedParen, tok.span())),
                    _ => return Err(self.expected("an operator or ')'")),
                }
                self.leave();
                Ok(e)
            }
            _ => Err(self.expected(match self.prev {
                Tok::Plus => "an expression after '+'",
                Tok::Minus => "an expression after '-'",
                Tok::Star => "an expression after '*'",
                Tok::Slash => "an expression after '/'",
                Tok::Caret => "an exponent after '^'",
                Tok::LParen => "an expression after '('",
                Tok::Comma => "an argument after ','",
                Tok::Num | Tok::Ident { .. } | Tok::RParen | Tok::End => "an expression",
            })),
        }
    }

    fn number(&mut self, tok: Token) -> PResult<ExprId> {
        let s = &self.text[tok.start..tok.end];
        let out_of_range = || self.error(ParseErrorKind::NumberOutOfRange, tok.span());
        if s == "." {
            return Err(self.expected("a number"));
        }
        let n = if s.bytes().all(|b| b.is_ascii_digit()) {
            let n: i128 = s.parse().map_err(|_| out_of_range())?;
            Number::Rational(Rational::int(n))
        } else {
            let x: f64 = s.parse().map_err(|_| self.expected("a number"))?;
            if !x.is_finite() {
                return Err(out_of_range());
            }
            Number::float(x)
        };
        Ok(self.pool.number(n))
    }

    /// A name: `pi`, a function call, or a symbol.
    fn name(&mut self, tok: Token, name_end: usize) -> PResult<ExprId> {
        let name = &self.text[tok.start..name_end];
        let primes = (tok.end - name_end) as u8;
        if name == "pi" {
            if primes > 0 {
                return Err(self.error(ParseErrorKind::PrimedConstant, tok.span()));
            }
            self.bump()?;
            return Ok(self.pool.pi());
        }
        if primes == 0 {
            if let Some((callee, fname)) = Callee::from_name(name) {
                self.bump()?;
                if self.tok.kind != Tok::LParen {
                    return Err(self.error(ParseErrorKind::MissingCall { name: fname }, tok.span()));
                }
                return self.call(tok, callee, fname);
            }
        }
        self.bump()?;
        if self.tok.kind == Tok::LParen && primes == 0 {
            let name = name.to_string();
            return Err(self.error(ParseErrorKind::UnknownFunction { name }, tok.span()));
        }
        if let Some(known) = self.opts.known {
            if !known(name, primes) {
                let name = self.text[tok.start..tok.end].to_string();
                return Err(self.error(ParseErrorKind::UnknownName { name }, tok.span()));
            }
        }
        let e = self.pool.var(name, primes);
        self.check_nodes(e, tok.span())
    }

    /// The arguments of a call; the lookahead is its `(`.
    fn call(&mut self, name_tok: Token, callee: Callee, fname: &'static str) -> PResult<ExprId> {
        let open = self.tok;
        self.enter()?;
        self.bump()?;
        let mut args = vec![self.sum()?];
        loop {
            match self.tok.kind {
                Tok::Comma => {
                    self.bump()?;
                    args.push(self.sum()?);
                }
                Tok::RParen => break,
                Tok::End => return Err(self.error(ParseErrorKind::UnclosedParen, open.span())),
                _ => return Err(self.expected("an operator, ',' or ')'")),
            }
        }
        let span = Span::new(name_tok.start, self.tok.end);
        self.bump()?;
        self.leave();
        if args.len() != callee.arity() {
            let kind = ParseErrorKind::WrongArgCount { name: fname, expected: callee.arity(), found: args.len() };
            return Err(self.error(kind, span));
        }
        let e = match callee {
            Callee::Unary(f) => self.pool.func(f, args[0]),
            Callee::Sqrt => self.pool.sqrt(args[0]),
            Callee::Atan2 => self.pool.atan2(args[0], args[1]),
        };
        self.check_nodes(e, span)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parses `input` and prints it back.
    #[track_caller]
    fn check(input: &str, expect: &str) {
        let mut pool = Pool::default();
        let e = pool.parse(input).unwrap_or_else(|err| panic!("{input:?}: {err}"));
        assert_eq!(pool.display(e).to_string(), expect, "{input:?}");
    }

    /// Fails to parse `input` with message `expect`, pointing at the text `at`
    /// (the first occurrence of `at` in `input`, or the end when it is empty).
    #[track_caller]
    fn check_err(input: &str, expect: &str, at: &str) {
        let mut pool = Pool::default();
        let err = pool.parse(input).expect_err(input);
        assert_eq!(err.to_string(), expect, "{input:?}");
        let start = if at.is_empty() { input.len() } else { input.find(at).expect("`at` occurs in the input") };
        assert_eq!(err.span, Span::new(start, start + at.len()), "{input:?}: {err}");
    }

    #[test]
    fn grammar() {
        check("1/2", "1/2");
        check("2", "2");
        check("0.5", "0.5");
        check(".5", "0.5");
        check("1e-3", "0.001");
        check("2.5E+2", "250.0");
        check("-x^2", "-x^2");
        check("(-x)^2", "x^2");
        check("2^-1", "1/2");
        check("x^-y^2", "1/x^y^2");
        check("x^y^z", "x^y^z");
        check("(x^y)^z", "(x^y)^z");
        check("x**2", "x^2");
        check("x**-1", "1/x");
        check("a - b - c", "a - b - c");
        check("a/b/c", "a/(b*c)");
        check("a/(b/c)", "a*c/b");
        check("--x", "x");
        check("+x", "x");
        check("x*-y", "-x*y");
        check("q' + q''", "q' + q''");
        check("p_q + t", "p_q + t");
        check("pi", "pi");
        check("ln(x)", "log(x)");
        check("sqrt(x)", "sqrt(x)");
        check("atan2(y, x)", "atan2(y, x)");
        check("  sin ( x )\n", "sin(x)");
        check("-(x + y)/x", "-(x + y)/x");
    }

    #[test]
    fn errors_say_what_was_expected_and_where() {
        check_err("", "expected an expression, found end of input", "");
        check_err("x +", "expected an expression after '+', found end of input", "");
        check_err("x + * y", "expected an expression after '+', found '*'", "*");
        check_err("2x", "expected an operator, found 'x'", "x");
        let hint = |text: &str| Pool::default().parse(text).err().and_then(|e| e.hint(text));
        assert_eq!(hint("2x").as_deref(), Some("a product needs its '*': write 2*x"));
        assert_eq!(hint("m*l x'").as_deref(), Some("a product needs its '*': write l*x'"));
        assert_eq!(hint("3(x+1)").as_deref(), Some("a product needs its '*': write 3*(...)"));
        assert_eq!(hint("(x+1)y").as_deref(), Some("a product needs its '*': write (...)*y"));
        assert_eq!(hint("x +* y"), None);
        check_err("2 x", "expected an operator, found 'x'", "x");
        check_err("(x", "unclosed parenthesis", "(");
        check_err("sin(x", "unclosed parenthesis", "(");
        check_err("x)", "unexpected ')'", ")");
        check_err("()", "expected an expression after '(', found ')'", ")");
        check_err("(2 x)", "expected an operator or ')', found 'x'", "x");
        check_err("x^", "expected an exponent after '^', found end of input", "");
        check_err("foo(x)", "unknown function 'foo'", "foo");
        check_err("sin(x, y)", "function 'sin' takes 1 argument, found 2", "sin(x, y)");
        check_err("atan2(x)", "function 'atan2' takes 2 arguments, found 1", "atan2(x)");
        check_err("sqrt x", "function 'sqrt' needs its argument in parentheses, as in sqrt(x)", "sqrt");
        check_err("q'''", "at most two primes are allowed (q' is a velocity, q'' an acceleration)", "q'''");
        check_err("pi'", "'pi' is a constant and has no time derivative", "pi'");
        check_err("x + é", "unexpected character 'é'", "é");
        check_err("x # y", "unexpected character '#'", "#");
        check_err("' x", "unexpected character '''", "'");
        check_err("1e999", "number out of range", "1e999");
        check_err(
            "1 + 170141183460469231731687303715884105728",
            "number out of range",
            "170141183460469231731687303715884105728",
        );
        check_err("x.", "expected an operator, found '.'", ".");
        check_err("2.5.3", "expected an operator, found '.3'", ".3");
        check_err("f(x", "unknown function 'f'", "f");
    }

    #[test]
    fn known_names_are_checked_with_their_primes() {
        let known = |name: &str, primes: u8| matches!((name, primes), ("q", 0..=2) | ("m" | "t", 0));
        let opts = ParseOptions::default().with_known(&known);
        let mut pool = Pool::default();
        assert!(pool.parse_with("m*q'' + sin(q) + pi*t", &opts).is_ok());
        let err = pool.parse_with("m*q' + x", &opts).unwrap_err();
        assert_eq!((err.to_string(), err.span), ("unknown name 'x'".to_string(), Span::new(7, 8)));
        let err = pool.parse_with("m' + q", &opts).unwrap_err();
        assert_eq!((err.to_string(), err.span), ("unknown name 'm''".to_string(), Span::new(0, 2)));
    }

    #[test]
    fn nesting_is_bounded_without_overflowing_the_stack() {
        let limit = Limits::default().max_depth;
        let deep = |open: &str, close: &str, n: usize| format!("{}x{}", open.repeat(n), close.repeat(n));
        let mut pool = Pool::default();
        assert!(pool.parse(&deep("(", ")", limit)).is_ok());
        for text in [
            deep("(", ")", limit + 1),
            deep("(", ")", 10_000),
            deep("(", "", 10_000),
            deep("-", "", 10_000),
            deep("- ", "", 10_000),
            deep("x^", "", 10_000),
            deep("2^-", "", 10_000),
            deep("sin(", ")", 10_000),
            deep("atan2(1, ", ")", 5_000),
        ] {
            let err = pool.parse(&text).unwrap_err();
            assert_eq!(err.kind, ParseErrorKind::TooDeep { limit }, "{}", &text[..20]);
        }
        let err = pool.parse(&deep("(", ")", 65)).unwrap_err();
        assert_eq!(err.span, Span::new(64, 65));
    }

    #[test]
    fn limits_are_configurable() {
        let mut pool = Pool::default();
        let long = "x + ".repeat(30_000) + "x";
        let err = pool.parse(&long).unwrap_err();
        assert_eq!(err.kind, ParseErrorKind::TooLong { limit: 100_000 });
        let big = Limits { max_len: 200_000, ..Limits::default() };
        assert!(pool.parse_with(&long, &ParseOptions::default().with_limits(big)).is_ok());

        let shallow = ParseOptions::default().with_limits(Limits { max_depth: 2, ..Limits::default() });
        assert!(pool.parse_with("((x))", &shallow).is_ok());
        assert!(pool.parse_with("(((x)))", &shallow).is_err());

        let small = ParseOptions::default().with_limits(Limits { max_nodes: 5, ..Limits::default() });
        let mut fresh = Pool::default();
        let err = fresh.parse_with("a + b + c + d + e + f", &small).unwrap_err();
        assert_eq!(err.kind, ParseErrorKind::TooManyNodes { limit: 5 });
    }

    #[test]
    fn long_flat_sums_and_products_parse_quickly() {
        // Chains are collected and canonicalized once, not one operator at a time.
        let mut pool = Pool::default();
        let sum: Vec<String> = (0..5_000).map(|i| format!("x{i}")).collect();
        let e = pool.parse(&sum.join(" + ")).unwrap();
        assert!(matches!(pool.node(e), crate::Node::Add(ts) if ts.len() == 5_000));
        let e = pool.parse(&sum.join("*")).unwrap();
        assert!(matches!(pool.node(e), crate::Node::Mul(fs) if fs.len() == 5_000));
    }

    #[test]
    fn overflowing_powers_do_not_panic() {
        let mut pool = Pool::default();
        for text in ["(-2)^127", "x/(-2)^127", "(-1/2)^127", "2^127", "(-2)^128", "1e300*1e300"] {
            let _ = pool.parse(text);
        }
    }

    #[test]
    fn huge_exponents_and_overflowing_constants_are_errors() {
        check_err("x^1000000000", "exponent 1000000000 is larger than 1000 in magnitude", "1000000000");
        check_err("x^-2000", "exponent -2000 is larger than 1000 in magnitude", "-2000");
        check_err("1e300*1e300", "the constant overflows a 64-bit float", "1e300*1e300");
        check("r^-12", "1/r^12");
    }

    /// A constant without a value is an error where it is written, so that no
    /// product with zero or cancellation can make it vanish; a large value
    /// that overflows a float is not one.
    #[test]
    fn undefined_constants_are_errors_where_they_are_written() {
        check_err("0*log(0)", "log(0) has no finite value (it evaluates to -inf)", "log(0)");
        check_err("(2/0)*x^2", "division by zero", "0");
        check_err("2*(1/0)", "division by zero", "0");
        check_err("0*sqrt(-1)", "sqrt(-1) has no finite value (it evaluates to NaN)", "sqrt(-1)");
        check_err("x^2/(x-x)", "division by zero", "(x-x)");
        check_err("0*asin(2)", "asin(2) has no finite value (it evaluates to NaN)", "asin(2)");
        check("0*exp(1000)", "0");
        check("1/(-64)^171", "1/(-64)^171");
        // Found by fuzzing: an odd function takes the sign out (asin(-2) is
        // -asin(2)), and the undefined value sat one level down.
        check_err("asin(-2)", "asin(-2) has no finite value (it evaluates to NaN)", "asin(-2)");
        check_err(
            "x + atan(1)*asin(-1000/2)",
            "asin(-1000/2) has no finite value (it evaluates to NaN)",
            "asin(-1000/2)",
        );
    }

    /// Found by fuzzing: `0^-x^2` read, and its derivative printed as
    /// `x*log(0)/0^x^2`, which has no value and does not read back.
    #[test]
    fn a_power_of_zero_needs_a_numeric_exponent() {
        let message = |text: &str| {
            format!("{text} is a power of zero with a variable exponent: 0 or no value by the exponent's sign")
        };
        check_err("m*x'^2/2 - 0^- x^2/2", &message("0^- x^2"), "0^- x^2");
        check_err("(x - x)^y", &message("(x - x)^y"), "(x - x)^y");
        check_err("2*0^(t + 1)", &message("0^(t + 1)"), "0^(t + 1)");
        check("0^2*x + 0^(1/2)", "0");
    }

    /// Found by fuzzing: numeric factors fold into one coefficient, which may
    /// overflow although no literal does; it printed as `inf`, a symbol.
    #[test]
    fn a_folded_coefficient_that_overflows_is_an_error() {
        check_err("x/1e-300*y/1e-300", "the constant overflows a 64-bit float", "x/1e-300*y/1e-300");
        check_err("1e300*x*1e300", "the constant overflows a 64-bit float", "1e300*x*1e300");
        check("1e300*x*1e-300", "1.0*x");
    }

    /// Exponents that folding makes are held to the same limit as written ones,
    /// so that whatever is read prints as text that reads back.
    #[test]
    fn folded_exponents_are_held_to_the_limit() {
        check_err("(((x^999)^999)^999)", "exponent 998001 is larger than 1000 in magnitude", "(x^999)^999");
        check_err("x^999*x^999", "exponent 1998 is larger than 1000 in magnitude", "x^999*x^999");
        check_err("(x*y^2)^600", "exponent 1200 is larger than 1000 in magnitude", "(x*y^2)^600");
        check("(x^10)^100", "x^1000");
    }
}
