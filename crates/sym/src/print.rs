//! The printer: one walk over an expression, written in the expression
//! language (text that parses back to the same id), in LaTeX, or in
//! presentation MathML.
//!
//! Enter with [`Pool::print`] and a preset of [`PrintOptions`]
//! ([`PrintOptions::text`], [`PrintOptions::latex`], [`PrintOptions::mathml`]),
//! or the shorthands [`Pool::display`], [`Pool::latex`] and [`Pool::mathml`];
//! each returns a value that implements
//! [`std::fmt::Display`], so `pool.display(e).to_string()` or
//! `format!("{}", pool.latex(e))`.
//!
//! The printer reads the canonical form once for both notations: a product is
//! a sign, a numeric coefficient `p/q`, the factors above the fraction bar and
//! the factors below it (powers with a negative exponent), so `m*l^2*q'^2/2`,
//! `-g*sin(q)/l` and `x/(2*y)` come out as people write them. It builds the
//! text of a node bottom-up together with the precedence of its outermost
//! operator, and the parent adds the parentheses that precedence requires, and
//! no more. The notation decides only the tokens (names, numbers, functions,
//! parentheses, how factors join, how a fraction and an exponent are written)
//! and the forms only the typeset notations have (`\sqrt[3]{x}`,
//! `\sin^{2}{\left(q \right)}`, no parentheses inside `\frac`). MathML
//! follows LaTeX's every decision; each of its pieces is one element (a
//! composite one an `<mrow>`), so a piece can always be the base or the
//! exponent of an `<msup>` or a part of an `<mfrac>`.
//!
//! With a [`crate::Shared`] (see `shared.rs`) the walk stops at the named nodes and
//! writes their names (`w12`, `w_{12}`, `<msub><mi>w</mi><mn>12</mn></msub>`)
//! instead; wherever it would look inside a child to choose a form (a term's
//! sign, a factor below the bar, a function raised to a power) a named child
//! counts as a name, an atom with nothing to look into.
//!
//! The text is checked by a property test: parsing it gives back the same
//! [`ExprId`]. Symbols whose names are not names of the language (a symbol
//! called `pi` or `sin`, or `"x y"`, built directly through [`Pool::symbol`])
//! print as they are and cannot round-trip.

use crate::expr::{ExprId, Func, Node, Pool, Symbol};
use crate::number::{Number, Rational};
use std::fmt;

/// How [`Pool::print`] writes an expression; start from a preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrintOptions {
    mode: PrintMode,
}

/// The notation a printer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrintMode {
    /// The expression language, with minimal parentheses: the text parses back.
    Text,
    /// LaTeX math (no surrounding `$`): `\frac`, `\sqrt`, `\dot{\theta}` for a
    /// first derivative, Greek letters for Greek names.
    Latex,
    /// Presentation MathML without the surrounding `<math>` element, with
    /// LaTeX's layout: `<mfrac>`, `<msqrt>`, `<msup>`, a dot accent for a
    /// first derivative, Greek letters for Greek names; `<`, `>` and `&` in
    /// names escaped.
    MathMl,
}

impl PrintOptions {
    /// Text in the expression language, which parses back to the same expression.
    pub fn text() -> PrintOptions {
        PrintOptions { mode: PrintMode::Text }
    }

    /// LaTeX math.
    pub fn latex() -> PrintOptions {
        PrintOptions { mode: PrintMode::Latex }
    }

    /// Presentation MathML, to go inside a `<math>` element.
    pub fn mathml() -> PrintOptions {
        PrintOptions { mode: PrintMode::MathMl }
    }

    /// The notation written.
    pub fn mode(&self) -> PrintMode {
        self.mode
    }
}

impl Default for PrintOptions {
    /// [`PrintOptions::text`].
    fn default() -> PrintOptions {
        PrintOptions::text()
    }
}

/// Nodes written as numbered names (`w12`) instead of their trees: those a
/// printout of shared subexpressions names (`crate::Shared`, which depends on
/// the printer, not the printer on it).
pub(crate) trait Names {
    /// The number of the name that stands for `id` (`w12`: 12), if one does.
    fn number_of(&self, id: ExprId) -> Option<usize>;
}

/// An expression to print with its options; see [`Pool::print`].
#[derive(Clone, Copy)]
pub struct Printed<'a> {
    pool: &'a Pool,
    id: ExprId,
    options: PrintOptions,
    /// The named nodes, written as their names.
    names: Option<&'a dyn Names>,
    /// Whether `id` is written out even when it is named (the right side of
    /// its definition).
    defining: bool,
}

impl<'a> Printed<'a> {
    /// `id` with the nodes `names` holds written as their names; when
    /// `defining`, `id` itself is written out (the right side of its definition).
    pub(crate) fn with_names(
        pool: &'a Pool,
        id: ExprId,
        options: PrintOptions,
        names: &'a dyn Names,
        defining: bool,
    ) -> Printed<'a> {
        Printed { pool, id, options, names: Some(names), defining }
    }
}

impl Pool {
    /// The expression `id` written as `options` say.
    pub fn print(&self, id: ExprId, options: PrintOptions) -> Printed<'_> {
        Printed { pool: self, id, options, names: None, defining: false }
    }

    /// The expression in the expression language, with minimal parentheses
    /// ([`PrintOptions::text`]). Parsing the text gives back `id`.
    pub fn display(&self, id: ExprId) -> Printed<'_> {
        self.print(id, PrintOptions::text())
    }

    /// The expression as LaTeX math ([`PrintOptions::latex`]).
    pub fn latex(&self, id: ExprId) -> Printed<'_> {
        self.print(id, PrintOptions::latex())
    }

    /// The expression as presentation MathML ([`PrintOptions::mathml`]), one
    /// element to put inside `<math>`.
    pub fn mathml(&self, id: ExprId) -> Printed<'_> {
        self.print(id, PrintOptions::mathml())
    }
}

impl fmt::Display for Printed<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let printer = Printer {
            pool: self.pool,
            mode: self.options.mode,
            names: self.names,
            top: self.defining.then_some(self.id),
        };
        f.write_str(&printer.expr(self.id).text)
    }
}

impl fmt::Debug for Printed<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

// ---- reading the canonical form ----------------------------------------------

/// How tightly printed text binds, loosest first.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
enum Prec {
    /// `a + b`.
    Sum,
    /// A leading minus: `-x`, `-2*y`.
    Neg,
    /// `a*b`, `a/b`, `1/2`.
    Product,
    /// `a^b`.
    Power,
    /// Names, numbers, calls, parenthesized text.
    Atom,
}

/// Printed text and the precedence of its outermost operator.
struct Piece {
    text: String,
    prec: Prec,
}

impl Piece {
    fn new(text: impl Into<String>, prec: Prec) -> Piece {
        Piece { text: text.into(), prec }
    }
}

/// A positive exponent to print: a node, a number, or a product with a
/// coefficient (the negation of a negative exponent, which the printer cannot
/// build because it only reads the pool).
#[derive(Clone, Copy)]
enum Exp<'a> {
    Id(ExprId),
    Num(Number),
    Mul(Number, &'a [ExprId]),
}

/// A negative number or a product with a negative coefficient, split into the
/// absolute coefficient and the other factors: `-3*x` is `(3, [x])`.
fn negated(pool: &Pool, id: ExprId) -> Option<(Number, &[ExprId])> {
    match pool.node(id) {
        Node::Num(n) if n.is_negative() => Some((abs(*n), &[])),
        Node::Mul(fs) => match pool.as_number(fs[0]) {
            Some(c) if c.is_negative() => Some((abs(c), &fs[1..])),
            _ => None,
        },
        _ => None,
    }
}

/// A product split into its coefficient and the other factors.
fn coeff_factors(pool: &Pool, fs: &[ExprId]) -> (Number, usize) {
    match pool.as_number(fs[0]) {
        Some(c) => (c, 1),
        None => (Number::ONE, 0),
    }
}

/// The absolute value without leaving exact arithmetic (`Number::abs` of
/// `i128::MIN` would fall back to a float).
fn abs(n: Number) -> Number {
    match n {
        Number::Rational(r) if r.is_negative() => match r.checked_neg() {
            Some(r) => Number::Rational(r),
            None => n,
        },
        Number::Float(x) => Number::float(x.abs()),
        r => r,
    }
}

/// If `id` is a power printed below a fraction bar, its base and the positive
/// exponent: `x^-2` is `(x, 2)`, `x^(-y)` is `(x, y)`.
///
/// A power of a number qualifies only when the base is a nonzero rational and
/// the exponent rational, because only then does the positive power fold
/// exactly when the negative one does (`0^-1` stays as it is, `0^1` is `0`).
fn below_bar(pool: &Pool, id: ExprId) -> Option<(ExprId, Exp<'_>)> {
    let Node::Pow(base, exp) = pool.node(id) else {
        return None;
    };
    let base_num = pool.as_number(*base);
    match pool.node(*exp) {
        Node::Num(e) if e.is_negative() => {
            let ok = match (base_num, e) {
                (None, _) => true,
                (Some(Number::Rational(b)), Number::Rational(_)) => !b.is_zero(),
                _ => false,
            };
            let pos = abs(*e);
            let same_kind =
                matches!((e, pos), (Number::Rational(_), Number::Rational(_)) | (Number::Float(_), Number::Float(_)));
            (ok && same_kind).then_some((*base, Exp::Num(pos)))
        }
        Node::Mul(fs) => match pool.as_number(fs[0]) {
            Some(c) if c.is_negative() => {
                let pos = abs(c);
                let same_kind = matches!(
                    (c, pos),
                    (Number::Rational(_), Number::Rational(_)) | (Number::Float(_), Number::Float(_))
                );
                same_kind.then_some((*base, Exp::Mul(pos, &fs[1..])))
            }
            _ => None,
        },
        _ => None,
    }
}

/// The numeric value of an exponent, if it is a number.
fn exp_number(pool: &Pool, exp: Exp<'_>) -> Option<Number> {
    match exp {
        Exp::Id(e) => pool.as_number(e),
        Exp::Num(n) => Some(n),
        Exp::Mul(..) => None,
    }
}

fn is_rational(n: Option<Number>, num: i128, den: i128) -> bool {
    matches!(n, Some(Number::Rational(r)) if Rational::new(num, den) == Some(r))
}

/// The integer `n` such that the exponent is `1/n`, for `n >= 2`.
fn root_index(n: Option<Number>) -> Option<i128> {
    match n {
        Some(Number::Rational(r)) if r.numer() == 1 && r.denom() >= 2 => Some(r.denom()),
        _ => None,
    }
}

/// A product split around the fraction bar.
struct Fraction<'a> {
    /// `|coefficient|` when it is a float.
    float: Option<f64>,
    /// Numerator of an exact `|coefficient|`.
    p: i128,
    /// Denominator of an exact coefficient.
    q: i128,
    above: Vec<ExprId>,
    /// Bases and positive exponents of the factors below the bar.
    below: Vec<(ExprId, Exp<'a>)>,
}

/// `factors` split around the bar; `opaque` factors (named ones) stay above it.
fn fraction<'a>(pool: &'a Pool, coeff: Number, factors: &'a [ExprId], opaque: impl Fn(ExprId) -> bool) -> Fraction<'a> {
    let (float, p, q) = match coeff {
        Number::Rational(r) => (None, r.numer(), r.denom()),
        Number::Float(x) => (Some(x), 1, 1),
    };
    let mut above = Vec::new();
    let mut below = Vec::new();
    for &f in factors {
        match below_bar(pool, f).filter(|_| !opaque(f)) {
            Some(b) => below.push(b),
            None => above.push(f),
        }
    }
    Fraction { float, p, q, above, below }
}

// ---- the walk -------------------------------------------------------------------

/// MathML's invisible function application, between `sin` and `(q)`.
const APPLY: &str = "<mo>&#x2061;</mo>";
/// MathML's minus sign (U+2212, not the hyphen).
const MINUS: &str = "<mo>&#x2212;</mo>";
/// MathML's invisible times with a thin space around it, between a word and its neighbour.
const SPACED_TIMES: &str = "<mo lspace=\"0.17em\" rspace=\"0.17em\">&#x2062;</mo>";

struct Printer<'a> {
    pool: &'a Pool,
    mode: PrintMode,
    /// The named nodes, if any: each is written as its name.
    names: Option<&'a dyn Names>,
    /// The expression defined, written out although it is named.
    top: Option<ExprId>,
}

impl Printer<'_> {
    /// The number of the name `id` is written as, if it is named (and not
    /// the expression being defined).
    fn name_of(&self, id: ExprId) -> Option<usize> {
        self.names.filter(|_| Some(id) != self.top).and_then(|n| n.number_of(id))
    }

    /// Whether `id` is written as a name, so that nothing inside it shows.
    fn opaque(&self, id: ExprId) -> bool {
        self.name_of(id).is_some()
    }

    /// A named node's name: `w12`, `w_{12}`, `<msub><mi>w</mi><mn>12</mn></msub>`.
    fn name(&self, k: usize) -> Piece {
        let text = match self.mode {
            PrintMode::Text => format!("w{k}"),
            PrintMode::Latex => format!("w_{{{k}}}"),
            PrintMode::MathMl => format!("<msub><mi>w</mi><mn>{k}</mn></msub>"),
        };
        Piece::new(text, Prec::Atom)
    }

    fn expr(&self, id: ExprId) -> Piece {
        let pool = self.pool;
        if let Some(k) = self.name_of(id) {
            return self.name(k);
        }
        match pool.node(id) {
            Node::Num(n) => self.num(*n),
            Node::Pi => Piece::new(self.pick("pi", "\\pi", "<mi>π</mi>"), Prec::Atom),
            Node::Sym(s) => Piece::new(self.symbol(*s), Prec::Atom),
            Node::Func(f, a) => self.func(*f, *a, None),
            Node::Atan2(y, x) => {
                let (y, x) = (self.expr(*y).text, self.expr(*x).text);
                let text = match self.mode {
                    PrintMode::Text => format!("atan2({y}, {x})"),
                    PrintMode::Latex => format!("\\operatorname{{atan2}}{{\\left({y}, {x} \\right)}}"),
                    PrintMode::MathMl => {
                        format!("<mrow><mi>atan2</mi>{APPLY}<mrow><mo>(</mo>{y}<mo>,</mo>{x}<mo>)</mo></mrow></mrow>")
                    }
                };
                Piece::new(text, Prec::Atom)
            }
            Node::Add(ts) => self.sum(ts),
            Node::Mul(fs) => {
                let (c, skip) = coeff_factors(pool, fs);
                self.product(c.is_negative(), abs(c), &fs[skip..])
            }
            Node::Pow(b, e) => match below_bar(pool, id) {
                Some(_) => self.product(false, Number::ONE, &[id]),
                None => self.power(*b, Exp::Id(*e)),
            },
        }
    }

    /// The token of this notation.
    fn pick(&self, text: &'static str, latex: &'static str, mathml: &'static str) -> &'static str {
        match self.mode {
            PrintMode::Text => text,
            PrintMode::Latex => latex,
            PrintMode::MathMl => mathml,
        }
    }

    /// Pieces written next to each other, made one element in MathML (an `<mrow>`).
    fn group(&self, text: String) -> String {
        match self.mode {
            PrintMode::MathMl => format!("<mrow>{text}</mrow>"),
            _ => text,
        }
    }

    /// Digits: an `<mn>` in MathML.
    fn digits(&self, text: &str) -> String {
        match self.mode {
            PrintMode::MathMl => format!("<mn>{text}</mn>"),
            _ => text.to_string(),
        }
    }

    /// `p` in parentheses when it binds more loosely than `min`.
    fn paren(&self, p: Piece, min: Prec) -> String {
        if p.prec < min {
            let open = self.pick("(", "\\left(", "<mrow><mo>(</mo>");
            let close = self.pick(")", "\\right)", "<mo>)</mo></mrow>");
            format!("{open}{}{close}", p.text)
        } else {
            p.text
        }
    }

    /// Whether a fraction bar groups its parts, so that a lone numerator or
    /// denominator needs no parentheses (LaTeX's `\frac` and MathML's
    /// `<mfrac>`, not the text's `/`).
    fn bar_groups(&self) -> bool {
        self.mode != PrintMode::Text
    }

    fn symbol(&self, s: Symbol) -> String {
        match self.mode {
            PrintMode::Text => self.pool.symbol_text(s),
            PrintMode::Latex => tex_symbol(self.pool, s),
            PrintMode::MathMl => mathml_symbol(self.pool, s),
        }
    }

    /// `f(a)`, or typeset `f^{n}(a)` when `power` is given (`\sin^{2}{\left(q \right)}`).
    fn func(&self, f: Func, a: ExprId, power: Option<&str>) -> Piece {
        let arg = self.expr(a).text;
        let name = match (f, self.mode) {
            (_, PrintMode::Text) => return Piece::new(format!("{}({arg})", f.name()), Prec::Atom),
            (Func::Exp, PrintMode::Latex) => return Piece::new(format!("e^{{{arg}}}"), Prec::Power),
            (Func::Exp, PrintMode::MathMl) => return Piece::new(format!("<msup><mi>e</mi>{arg}</msup>"), Prec::Power),
            (Func::Abs, PrintMode::Latex) => return Piece::new(format!("\\left|{arg}\\right|"), Prec::Atom),
            (Func::Abs, PrintMode::MathMl) => {
                return Piece::new(format!("<mrow><mo>|</mo>{arg}<mo>|</mo></mrow>"), Prec::Atom);
            }
            (Func::Sin, _) => "sin",
            (Func::Cos, _) => "cos",
            (Func::Tan, _) => "tan",
            (Func::Asin, _) => "arcsin",
            (Func::Acos, _) => "arccos",
            (Func::Atan, _) => "arctan",
            (Func::Sinh, _) => "sinh",
            (Func::Cosh, _) => "cosh",
            (Func::Tanh, _) => "tanh",
            (Func::Log, _) => "log",
        };
        let text = if self.mode == PrintMode::Latex {
            let power = power.map(|p| format!("^{{{p}}}")).unwrap_or_default();
            format!("\\{name}{power}{{\\left({arg} \\right)}}")
        } else {
            let name = match power {
                Some(p) => format!("<msup><mi>{name}</mi>{p}</msup>"),
                None => format!("<mi>{name}</mi>"),
            };
            format!("<mrow>{name}{APPLY}<mrow><mo>(</mo>{arg}<mo>)</mo></mrow></mrow>")
        };
        Piece::new(text, Prec::Atom)
    }

    fn num(&self, n: Number) -> Piece {
        let a = self.num_abs(abs(n));
        if n.is_negative() {
            Piece::new(self.group(format!("{}{}", self.pick("-", "-", MINUS), a.text)), Prec::Neg)
        } else {
            a
        }
    }

    /// A number that is not negative.
    fn num_abs(&self, n: Number) -> Piece {
        match (n, self.mode) {
            (Number::Rational(r), _) if r.is_integer() => Piece::new(self.digits(&r.to_string()), Prec::Atom),
            (Number::Rational(r), PrintMode::Text) => Piece::new(r.to_string(), Prec::Product),
            (Number::Rational(r), PrintMode::Latex) => {
                Piece::new(format!("\\frac{{{}}}{{{}}}", r.numer().unsigned_abs(), r.denom()), Prec::Product)
            }
            (Number::Rational(r), PrintMode::MathMl) => Piece::new(
                format!("<mfrac><mn>{}</mn><mn>{}</mn></mfrac>", r.numer().unsigned_abs(), r.denom()),
                Prec::Product,
            ),
            (Number::Float(_), PrintMode::Text) => Piece::new(n.to_string(), Prec::Atom),
            (Number::Float(_), PrintMode::Latex) => tex_float(&n.to_string()),
            (Number::Float(_), PrintMode::MathMl) => mathml_float(&n.to_string()),
        }
    }

    fn sum(&self, ts: &[ExprId]) -> Piece {
        let mut out = String::new();
        for (i, &t) in ts.iter().enumerate() {
            let neg = if self.opaque(t) { None } else { negated(self.pool, t) };
            out.push_str(match (i, neg.is_some()) {
                (0, false) => "",
                (0, true) => self.pick("-", "- ", MINUS),
                (_, false) => self.pick(" + ", " + ", "<mo>+</mo>"),
                (_, true) => self.pick(" - ", " - ", MINUS),
            });
            if let Some((c, fs)) = neg {
                out.push_str(&self.paren(self.product(false, c, fs), Prec::Product));
            } else {
                out.push_str(&self.paren(self.expr(t), Prec::Neg));
            }
        }
        Piece::new(self.group(out), Prec::Sum)
    }

    /// `±coeff * factors`, with the factors that have negative exponents below a bar.
    fn product(&self, negative: bool, coeff: Number, factors: &[ExprId]) -> Piece {
        if negative {
            let p = self.paren(self.product(false, coeff, factors), Prec::Product);
            return Piece::new(self.group(format!("{}{p}", self.pick("-", "- ", MINUS))), Prec::Neg);
        }
        if factors.is_empty() {
            return self.num_abs(coeff);
        }
        if coeff.is_one()
            && factors.len() == 1
            && (self.opaque(factors[0]) || below_bar(self.pool, factors[0]).is_none())
        {
            return self.expr(factors[0]);
        }
        let fr = fraction(self.pool, coeff, factors, |f| self.opaque(f));
        let mut above: Vec<String> = Vec::new();
        if let Some(x) = fr.float {
            above.push(self.num_abs(Number::float(x)).text);
        } else if fr.p != 1 {
            above.push(self.digits(&fr.p.to_string()));
        }
        let lone_above = self.bar_groups() && above.is_empty() && fr.above.len() == 1 && !fr.below.is_empty();
        for &f in &fr.above {
            let p = self.expr(f);
            above.push(if lone_above { p.text } else { self.paren(p, Prec::Power) });
        }
        let mut below: Vec<String> = Vec::new();
        if fr.q != 1 {
            below.push(self.digits(&fr.q.to_string()));
        }
        let lone_below = self.bar_groups() && fr.below.len() == 1 && fr.q == 1;
        for &(b, e) in &fr.below {
            let p = self.power(b, e);
            below.push(if lone_below { p.text } else { self.paren(p, Prec::Power) });
        }
        let above = if above.is_empty() { self.digits("1") } else { self.join_factors(&above) };
        if below.is_empty() {
            return Piece::new(above, Prec::Product);
        }
        let text = match self.mode {
            PrintMode::Text => {
                // `2*(x - 1)` would parse as `2*x - 2` (a number times one sum
                // distributes), so a lone sum below the bar keeps its number apart.
                let lone_sum = fr.q != 1
                    && matches!(fr.below[..], [(b, e)] if is_rational(exp_number(self.pool, e), 1, 1)
                    && !self.opaque(b) && matches!(self.pool.node(b), Node::Add(_)));
                match below.len() {
                    1 => format!("{above}/{}", below[0]),
                    _ if lone_sum => format!("{above}/{}/{}", below[1], below[0]),
                    _ => format!("{above}/({})", below.join("*")),
                }
            }
            PrintMode::Latex | PrintMode::MathMl => {
                let below = match below.len() {
                    1 => below.swap_remove(0),
                    _ => self.join_factors(&below),
                };
                match self.mode {
                    PrintMode::Latex => format!("\\frac{{{above}}}{{{below}}}"),
                    _ => format!("<mfrac>{above}{below}</mfrac>"),
                }
            }
        };
        Piece::new(text, Prec::Product)
    }

    /// Factors side by side: `a*b` in text; juxtaposed when typeset, with a
    /// centred dot before a factor that starts with a digit (so `2 \cdot 3^{x}`
    /// does not read as `23^x`). MathML joins the others with an invisible
    /// times, spaced when a word meets a neighbour (`lA lB`, not `lAlB`),
    /// and makes the product one `<mrow>`.
    fn join_factors(&self, parts: &[String]) -> String {
        let (plain, dot) = match self.mode {
            PrintMode::Text => return parts.join("*"),
            PrintMode::Latex => (" ", " \\cdot "),
            PrintMode::MathMl => ("<mo>&#x2062;</mo>", "<mo>&#x22C5;</mo>"),
        };
        let mut out = String::new();
        for (i, part) in parts.iter().enumerate() {
            if i > 0 {
                out.push_str(if self.starts_with_digit(part) {
                    dot
                } else if self.mode == PrintMode::MathMl && (starts_with_word(part) || ends_with_word(&parts[i - 1])) {
                    SPACED_TIMES
                } else {
                    plain
                });
            }
            out.push_str(part);
        }
        if parts.len() > 1 {
            self.group(out)
        } else {
            out
        }
    }

    /// Whether typeset text shows a digit first: `2`, `3^{x}`, `<msup><mn>3</mn>…`.
    fn starts_with_digit(&self, part: &str) -> bool {
        match self.mode {
            PrintMode::MathMl => first_leaf(part).starts_with("<mn>"),
            _ => part.starts_with(|c: char| c.is_ascii_digit()),
        }
    }

    /// `base ^ exp` for an exponent that prints without a leading minus
    /// (or a negative one on a numeric base, as `2^(-300)`).
    fn power(&self, base: ExprId, exp: Exp<'_>) -> Piece {
        let typeset = self.mode != PrintMode::Text;
        let n = exp_number(self.pool, exp);
        if is_rational(n, 1, 1) {
            return self.expr(base);
        }
        if is_rational(n, 1, 2) {
            let b = self.expr(base).text;
            let text = match self.mode {
                PrintMode::Text => format!("sqrt({b})"),
                PrintMode::Latex => format!("\\sqrt{{{b}}}"),
                PrintMode::MathMl => format!("<msqrt>{b}</msqrt>"),
            };
            return Piece::new(text, Prec::Atom);
        }
        if let (true, Some(k)) = (typeset, root_index(n)) {
            let b = self.expr(base).text;
            let text = match self.mode {
                PrintMode::Latex => format!("\\sqrt[{k}]{{{b}}}"),
                _ => format!("<mroot>{b}<mn>{k}</mn></mroot>"),
            };
            return Piece::new(text, Prec::Atom);
        }
        let e = match exp {
            Exp::Id(e) => self.expr(e),
            Exp::Num(n) => self.num(n),
            Exp::Mul(c, fs) => self.product(false, c, fs),
        };
        // Typeset, sin(q)^2 reads as \sin^{2}(q) when the exponent is a positive integer.
        if let (true, Node::Func(f, a), Some(Number::Rational(r))) = (typeset, self.pool.node(base), n) {
            if !self.opaque(base) && r.is_integer() && !r.is_negative() && !matches!(f, Func::Exp | Func::Abs) {
                return self.func(*f, *a, Some(&e.text));
            }
        }
        let b = self.paren(self.expr(base), Prec::Atom);
        let text = match self.mode {
            PrintMode::Text => format!("{b}^{}", self.paren(e, Prec::Power)),
            PrintMode::Latex => format!("{b}^{{{}}}", e.text),
            // A subscripted base carries the exponent above its subscript: θ₁².
            PrintMode::MathMl => match b.strip_prefix("<msub>").and_then(|b| b.strip_suffix("</msub>")) {
                Some(base_and_sub) => format!("<msubsup>{base_and_sub}{}</msubsup>", e.text),
                None => format!("<msup>{b}{}</msup>", e.text),
            },
        };
        Piece::new(text, Prec::Power)
    }
}

/// MathML from the first element that is seen first: past the opening tags
/// of rows, and of powers and subscripts, which show their base first.
fn first_leaf(part: &str) -> &str {
    let mut rest = part;
    while let Some(inner) = ["<mrow>", "<msup>", "<msub>", "<msubsup>"].iter().find_map(|tag| rest.strip_prefix(tag)) {
        rest = inner;
    }
    rest
}

/// Whether MathML shows a word of several letters first: `<mi>lA</mi>`,
/// `<msup><mi>lA</mi>…`, or a function's name.
fn starts_with_word(part: &str) -> bool {
    first_leaf(part).strip_prefix("<mi>").and_then(|r| r.split_once("</mi>")).is_some_and(|(word, _)| is_word(word))
}

/// Whether MathML shows a word of several letters last: `<mi>lA</mi>` alone.
fn ends_with_word(part: &str) -> bool {
    part.strip_prefix("<mi>").and_then(|r| r.strip_suffix("</mi>")).is_some_and(is_word)
}

/// Whether the text of an `<mi>` is a word, several letters set upright.
fn is_word(text: &str) -> bool {
    text.chars().count() > 1 && !text.contains('<')
}

// ---- names and numbers, typeset ----------------------------------------------------

/// A symbol in LaTeX: `\dot{\theta}_{1}` for `th1'`.
fn tex_symbol(pool: &Pool, s: Symbol) -> String {
    let (base, sub) = tex_name(pool.name_str(s.name));
    let base = match s.order {
        0 => base,
        1 => format!("\\dot{{{base}}}"),
        2 => format!("\\ddot{{{base}}}"),
        n => format!("{base}^{{({n})}}"),
    };
    match sub {
        Some(sub) => format!("{base}_{{{sub}}}"),
        None => base,
    }
}

/// A symbol in MathML, one element: `th1'` is θ with a dot over it, subscript 1.
///
/// The dot is an `<mover>` without `accent="true"`: an accent is placed by
/// the font's OpenType MATH table, and without a math font Chromium draws it
/// inside the letter (a θ with its dot hidden), while an over-script sits
/// above the letter in every font.
fn mathml_symbol(pool: &Pool, s: Symbol) -> String {
    let (base, sub) = mathml_name(pool.name_str(s.name));
    let base = match s.order {
        0 => base,
        1 => format!("<mover>{base}<mo>˙</mo></mover>"),
        2 => format!("<mover>{base}<mo>¨</mo></mover>"),
        n => format!("<msup>{base}<mrow><mo>(</mo><mn>{n}</mn><mo>)</mo></mrow></msup>"),
    };
    match sub {
        Some(sub) => format!("<msub>{base}{sub}</msub>"),
        None => base,
    }
}

/// A float in LaTeX: `1.5e-7` becomes `1.5 \cdot 10^{-7}`.
fn tex_float(text: &str) -> Piece {
    match text.split_once('e') {
        Some(("1", exp)) => Piece::new(format!("10^{{{exp}}}"), Prec::Power),
        Some((mantissa, exp)) => Piece::new(format!("{mantissa} \\cdot 10^{{{exp}}}"), Prec::Product),
        None => Piece::new(text, Prec::Atom),
    }
}

/// A float in MathML, as LaTeX writes it: `1.5e-7` is 1.5 ⋅ 10⁻⁷; `inf` is ∞.
fn mathml_float(text: &str) -> Piece {
    let ten_to = |exp: &str| match exp.strip_prefix('-') {
        Some(e) => format!("<msup><mn>10</mn><mrow>{MINUS}<mn>{e}</mn></mrow></msup>"),
        None => format!("<msup><mn>10</mn><mn>{exp}</mn></msup>"),
    };
    match text.split_once('e') {
        Some(("1", exp)) => Piece::new(ten_to(exp), Prec::Power),
        Some((mantissa, exp)) => {
            Piece::new(format!("<mrow><mn>{mantissa}</mn><mo>&#x22C5;</mo>{}</mrow>", ten_to(exp)), Prec::Product)
        }
        None if text == "inf" => Piece::new("<mi>∞</mi>", Prec::Atom),
        None if text.starts_with(|c: char| c.is_ascii_digit()) => Piece::new(format!("<mn>{text}</mn>"), Prec::Atom),
        None => Piece::new(format!("<mi>{}</mi>", escape_xml(text)), Prec::Atom),
    }
}

/// The subscript a name carries.
enum Subscript<'a> {
    /// Trailing digits: `th1`.
    Digits(&'a str),
    /// A name after the first `_`: `p_th`, itself typeset as a name.
    Name(&'a str),
}

/// A name split into its word and subscript, the same for every typeset
/// notation: `th1` is `(th, 1)`, `p_th` is `(p, th)`, `omega` is `(omega, None)`.
fn split_name(name: &str) -> (&str, Option<Subscript<'_>>) {
    if let Some((head, tail)) = name.split_once('_') {
        if !head.is_empty() && !tail.is_empty() {
            return (head, Some(Subscript::Name(tail)));
        }
    }
    let stem = name.trim_end_matches(|c: char| c.is_ascii_digit());
    if !stem.is_empty() && stem.len() < name.len() {
        return (stem, Some(Subscript::Digits(&name[stem.len()..])));
    }
    (name, None)
}

/// The LaTeX of a name, split into the base and an optional subscript:
/// `th1` is `(\theta, 1)`, `p_th` is `(p, \theta)`, `omega` is `(\omega, None)`.
fn tex_name(name: &str) -> (String, Option<String>) {
    let (word, sub) = split_name(name);
    let sub = sub.map(|sub| match sub {
        Subscript::Digits(digits) => digits.to_string(),
        Subscript::Name(name) => match tex_name(name) {
            (b, Some(s)) => format!("{b}_{{{s}}}"),
            (b, None) => b,
        },
    });
    (tex_word(word), sub)
}

/// The MathML of a name, split into the base and an optional subscript, each
/// one element: `th1` is `(<mi>θ</mi>, <mn>1</mn>)`.
fn mathml_name(name: &str) -> (String, Option<String>) {
    let (word, sub) = split_name(name);
    let sub = sub.map(|sub| match sub {
        Subscript::Digits(digits) => format!("<mn>{digits}</mn>"),
        Subscript::Name(name) => match mathml_name(name) {
            (b, Some(s)) => format!("<msub>{b}{s}</msub>"),
            (b, None) => b,
        },
    });
    (mathml_word(word), sub)
}

/// A name without subscript: a Greek letter, a single letter, or upright text.
fn tex_word(word: &str) -> String {
    if let Some((greek, _)) = greek(word) {
        return greek.to_string();
    }
    if word.chars().count() == 1 {
        return word.replace('_', "\\_");
    }
    format!("\\mathrm{{{}}}", word.replace('_', "\\_"))
}

/// A name without subscript in MathML: an `<mi>`, which sets a single letter
/// in italics and a longer word upright, as LaTeX's `\mathrm` does. Capital
/// Greek letters stay upright, as in LaTeX.
fn mathml_word(word: &str) -> String {
    match greek(word) {
        Some((_, letter)) if letter.starts_with(char::is_uppercase) => {
            format!("<mi mathvariant=\"normal\">{letter}</mi>")
        }
        Some((_, letter)) => format!("<mi>{letter}</mi>"),
        None => format!("<mi>{}</mi>", escape_xml(word)),
    }
}

/// Text inside a MathML element, with `&`, `<` and `>` escaped.
fn escape_xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            c => out.push(c),
        }
    }
    out
}

/// A Greek name's letter in LaTeX and in Unicode.
fn greek(word: &str) -> Option<(&'static str, &'static str)> {
    Some(match word {
        "alpha" | "al" => ("\\alpha", "α"),
        "beta" | "be" => ("\\beta", "β"),
        "gamma" | "ga" => ("\\gamma", "γ"),
        "delta" => ("\\delta", "δ"),
        "epsilon" | "eps" => ("\\epsilon", "ε"),
        "zeta" => ("\\zeta", "ζ"),
        "eta" => ("\\eta", "η"),
        "theta" | "th" => ("\\theta", "θ"),
        "iota" => ("\\iota", "ι"),
        "kappa" => ("\\kappa", "κ"),
        "lambda" | "lam" => ("\\lambda", "λ"),
        "mu" => ("\\mu", "μ"),
        "nu" => ("\\nu", "ν"),
        "xi" => ("\\xi", "ξ"),
        "pi" => ("\\pi", "π"),
        "rho" => ("\\rho", "ρ"),
        "sigma" => ("\\sigma", "σ"),
        "tau" => ("\\tau", "τ"),
        "upsilon" => ("\\upsilon", "υ"),
        "phi" | "ph" => ("\\phi", "φ"),
        "chi" => ("\\chi", "χ"),
        "psi" => ("\\psi", "ψ"),
        "omega" | "om" => ("\\omega", "ω"),
        "Gamma" => ("\\Gamma", "Γ"),
        "Delta" => ("\\Delta", "Δ"),
        "Theta" => ("\\Theta", "Θ"),
        "Lambda" => ("\\Lambda", "Λ"),
        "Xi" => ("\\Xi", "Ξ"),
        "Pi" => ("\\Pi", "Π"),
        "Sigma" => ("\\Sigma", "Σ"),
        "Upsilon" => ("\\Upsilon", "Υ"),
        "Phi" => ("\\Phi", "Φ"),
        "Psi" => ("\\Psi", "Ψ"),
        "Omega" => ("\\Omega", "Ω"),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parses `input`, prints it, and checks that the text parses back to the same id.
    #[track_caller]
    fn check(input: &str, expect: &str) {
        let mut pool = Pool::default();
        let e = pool.parse(input).unwrap_or_else(|err| panic!("{input:?}: {err}"));
        let text = pool.print(e, PrintOptions::text()).to_string();
        assert_eq!(text, expect, "{input:?}");
        assert_eq!(pool.display(e).to_string(), text);
        assert_eq!(pool.parse(&text), Ok(e), "{input:?} printed as {text:?} does not parse back");
    }

    /// Parses `input` and prints it as LaTeX.
    #[track_caller]
    fn check_latex(input: &str, expect: &str) {
        let mut pool = Pool::default();
        let e = pool.parse(input).unwrap_or_else(|err| panic!("{input:?}: {err}"));
        assert_eq!(pool.print(e, PrintOptions::latex()).to_string(), expect, "{input:?}");
        assert_eq!(pool.latex(e).to_string(), expect, "{input:?}");
    }

    /// Parses `input` and prints it as MathML.
    #[track_caller]
    fn check_mathml(input: &str, expect: &str) {
        let mut pool = Pool::default();
        let e = pool.parse(input).unwrap_or_else(|err| panic!("{input:?}: {err}"));
        assert_eq!(pool.print(e, PrintOptions::mathml()).to_string(), expect, "{input:?}");
        assert_eq!(pool.mathml(e).to_string(), expect, "{input:?}");
    }

    #[test]
    fn text() {
        check("m*l^2*q'^2/2 + m*g*l*cos(q)", "l^2*m*q'^2/2 + g*l*m*cos(q)");
        check("-g*sin(q)/l", "-g*sin(q)/l");
        check("x*y^-1", "x/y");
        check("x^-2", "1/x^2");
        check("x^(1/2)", "sqrt(x)");
        check("x^(-1/2)", "1/sqrt(x)");
        check("x^(2/3)", "x^(2/3)");
        check("x^(-3/2)", "1/x^(3/2)");
        check("(-1)^x", "(-1)^x");
        check("(-2)*x", "-2*x");
        check("(-2)^x", "(-2)^x");
        check("(1/2)^x", "(1/2)^x");
        check("2^(1/2)", "sqrt(2)");
        check("(-2*a)^(1/2)", "sqrt(-2*a)");
        check("(-2*a)^(1/3)", "(-2*a)^(1/3)");
        check("(x^2)^y", "(x^2)^y");
        check("sqrt(x)^y", "sqrt(x)^y");
        check("x^y^z", "x^y^z");
        check("1e300", "1e300");
        check("-0.5", "-0.5");
        check("-0.5*x", "-0.5*x");
        check("1.0*x", "1.0*x");
        check("0.5^x", "0.5^x");
        check("1/(a + b)", "1/(a + b)");
        check("1/(a*b)", "1/(a*b)");
        check("a/(b*c)", "a/(b*c)");
        check("x/2", "x/2");
        check("x - 1/2", "x - 1/2");
        check("3/(2*x)", "3/(2*x)");
        check("-1/x", "-1/x");
        check("x/(2*(x + y)*z)", "x/(2*z*(x + y))");
        check("(a + b)^-1/2", "1/(a + b)/2");
        check("-(x + y)/x", "-(x + y)/x");
        check("a - (x + y)/x", "a - (x + y)/x");
        check("2^(-x)", "1/2^x");
        check("x/sqrt(2)", "x/sqrt(2)");
        check("2^-300*x", "x/2^300");
        // A division by zero cannot be written (the parser refuses it), but
        // expressions built by code may hold one: it prints as a power.
        let mut pool = Pool::default();
        let x = pool.symbol("x");
        let (zero, zero_float) = (pool.zero(), pool.float(0.0));
        let (e, f) = (pool.div(x, zero), pool.div(x, zero_float));
        assert_eq!(
            (pool.display(e).to_string(), pool.display(f).to_string()),
            ("0^(-1)*x".into(), "0.0^(-1)*x".into())
        );
        check("exp(-x)", "exp(-x)");
        check("a - b + 2*c - 3", "a - b + 2*c - 3");
        check("atan2(y, -x)", "atan2(y, -x)");
        check("abs(x)*sign", "sign*abs(x)");
        check("t*p_q^2", "p_q^2*t");
    }

    #[test]
    fn latex() {
        check_latex("m*l^2*q'^2/2", "\\frac{l^{2} m \\dot{q}^{2}}{2}");
        check_latex("-g*sin(q)/l", "- \\frac{g \\sin{\\left(q \\right)}}{l}");
        check_latex("th1''", "\\ddot{\\theta}_{1}");
        check_latex("th1'^2*sin(th1 - th2)", "\\dot{\\theta}_{1}^{2} \\sin{\\left(\\theta_{1} - \\theta_{2} \\right)}");
        check_latex("p_th^2/(2*m*l^2)", "\\frac{p_{\\theta}^{2}}{2 l^{2} m}");
        check_latex("omega*Omega*lam", "\\Omega \\lambda \\omega");
        check_latex("al + be + ga + ph + om", "\\alpha + \\beta + \\gamma + \\omega + \\phi");
        check_latex("size*x_A", "\\mathrm{size} x_{A}");
        check_latex("1/sqrt(x^2 + 1)", "\\frac{1}{\\sqrt{x^{2} + 1}}");
        check_latex("(x + y)/z", "\\frac{x + y}{z}");
        check_latex("x^(1/3)", "\\sqrt[3]{x}");
        check_latex("x^(2/3)", "x^{\\frac{2}{3}}");
        check_latex("sin(q)^2", "\\sin^{2}{\\left(q \\right)}");
        check_latex("exp(-x)", "e^{- x}");
        check_latex("abs(x)", "\\left|x\\right|");
        check_latex("atan2(y, x)", "\\operatorname{atan2}{\\left(y, x \\right)}");
        check_latex("2*3^x", "2 \\cdot 3^{x}");
        check_latex("(a + b)^2*c", "c \\left(a + b\\right)^{2}");
        check_latex("1.5e-7*x", "1.5 \\cdot 10^{-7} x");
        check_latex("pi*r^2", "\\pi r^{2}");
        check_latex("(-1)^n", "\\left(-1\\right)^{n}");
        check_latex("x - 1/2", "x - \\frac{1}{2}");
    }

    #[test]
    fn mathml() {
        // A fraction, with LaTeX's grouping: no parentheses inside the bar.
        check_mathml("(x + y)/z", "<mfrac><mrow><mi>x</mi><mo>+</mo><mi>y</mi></mrow><mi>z</mi></mfrac>");
        check_mathml("x - 1/2", "<mrow><mi>x</mi><mo>&#x2212;</mo><mfrac><mn>1</mn><mn>2</mn></mfrac></mrow>");
        // A power of a velocity: the dot accent is the base.
        check_mathml("q'^2", "<msup><mover><mi>q</mi><mo>˙</mo></mover><mn>2</mn></msup>");
        check_mathml("th1''", "<msub><mover><mi>θ</mi><mo>¨</mo></mover><mn>1</mn></msub>");
        // A subscripted base takes its exponent above the subscript.
        check_mathml("th1^2", "<msubsup><mi>θ</mi><mn>1</mn><mn>2</mn></msubsup>");
        // A function of a Greek name, and its power written on the function.
        check_mathml(
            "sin(ph)",
            "<mrow><mi>sin</mi><mo>&#x2061;</mo><mrow><mo>(</mo><mi>φ</mi><mo>)</mo></mrow></mrow>",
        );
        check_mathml(
            "cos(th)^2",
            "<mrow><msup><mi>cos</mi><mn>2</mn></msup><mo>&#x2061;</mo><mrow><mo>(</mo><mi>θ</mi><mo>)</mo></mrow></mrow>",
        );
        // A subscripted momentum, squared, over a product.
        check_mathml(
            "p_th^2/(2*m)",
            "<mfrac><msubsup><mi>p</mi><mi>θ</mi><mn>2</mn></msubsup>\
             <mrow><mn>2</mn><mo>&#x2062;</mo><mi>m</mi></mrow></mfrac>",
        );
        check_mathml("p_th1", "<msub><mi>p</mi><msub><mi>θ</mi><mn>1</mn></msub></msub>");
        // A function's name is a word, spaced from its neighbours as LaTeX spaces `\sin`.
        check_mathml(
            "-g*sin(q)/l",
            &format!(
                "<mrow><mo>&#x2212;</mo><mfrac><mrow><mi>g</mi>{SPACED_TIMES}<mrow><mi>sin</mi><mo>&#x2061;</mo>\
                 <mrow><mo>(</mo><mi>q</mi><mo>)</mo></mrow></mrow></mrow><mi>l</mi></mfrac></mrow>"
            ),
        );
        check_mathml("lA*lB*m", &format!("<mrow><mi>lA</mi>{SPACED_TIMES}<mi>lB</mi>{SPACED_TIMES}<mi>m</mi></mrow>"));
        check_mathml("1/sqrt(x)", "<mfrac><mn>1</mn><msqrt><mi>x</mi></msqrt></mfrac>");
        check_mathml("x^(1/3)", "<mroot><mi>x</mi><mn>3</mn></mroot>");
        check_mathml("pi*r^2", "<mrow><mi>π</mi><mo>&#x2062;</mo><msup><mi>r</mi><mn>2</mn></msup></mrow>");
        check_mathml("2*3^x", "<mrow><mn>2</mn><mo>&#x22C5;</mo><msup><mn>3</mn><mi>x</mi></msup></mrow>");
        check_mathml(
            "(a + b)^2",
            "<msup><mrow><mo>(</mo><mrow><mi>a</mi><mo>+</mo><mi>b</mi></mrow><mo>)</mo></mrow><mn>2</mn></msup>",
        );
        check_mathml("exp(-x)", "<msup><mi>e</mi><mrow><mo>&#x2212;</mo><mi>x</mi></mrow></msup>");
        check_mathml("1.5e-7", "<mrow><mn>1.5</mn><mo>&#x22C5;</mo><msup><mn>10</mn><mrow><mo>&#x2212;</mo><mn>7</mn></mrow></msup></mrow>");
        check_mathml("Omega*x", "<mrow><mi mathvariant=\"normal\">Ω</mi><mo>&#x2062;</mo><mi>x</mi></mrow>");
        // Names built by code are escaped.
        let mut pool = Pool::default();
        let odd = pool.symbol("a<b&c");
        assert_eq!(pool.mathml(odd).to_string(), "<mi>a&lt;b&amp;c</mi>");
    }
}
