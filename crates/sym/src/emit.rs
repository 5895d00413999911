//! Straight-line source code from a tape, for code that leaves lagrange: C99
//! with nothing but libm, or Python with numpy ([`Tape::emit`]).
//!
//! Each instruction the outputs need becomes one assignment to a temporary
//! (`v12`), in the tape's order, so the common subexpressions the tape shares
//! are computed once in the written code too; an input is read where it is
//! used (`y[3]`), a constant is written where it is used, and an instruction no
//! output needs is left out (C's `-Wall -Werror` refuses unused variables).
//! Constants print by their shortest round-trip digits, so the code computes
//! with the tape's numbers. The functions are libm's (`sin`, `pow`, `fabs`) or
//! numpy's (`np.sin`, `np.power`, `np.abs`), which work elementwise: Python
//! code whose inputs are rows of an array computes every column at once.

use crate::eval::{Op, Tape};
use crate::expr::Func;

/// The language [`Tape::emit`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Language {
    /// C99 statements (`const double v3 = v1 * v2;`) calling libm.
    C,
    /// Python statements (`v3 = v1 * v2`) calling numpy as `np`.
    Python,
}

/// How the written statements read their inputs and store their outputs.
#[derive(Clone, Copy)]
pub struct Emit<'a> {
    /// The language.
    pub language: Language,
    /// Where input k is read, with `{}` for k (`y[{}]`, `p[{}]`): a function
    /// of k so that the state and the parameters can be two arrays.
    pub input: &'a dyn Fn(usize) -> String,
    /// The array the outputs are stored in (`out`: `out[0] = v12;`).
    pub output: &'a str,
    /// The indentation of every statement.
    pub indent: &'a str,
    /// The prefix of the temporaries (`v`), unique in the function written.
    pub temporary: &'a str,
}

impl Tape {
    /// The tape as statements in `emit.language` (see the module comment):
    /// the temporaries the outputs need, then `output[k] = …` for each output.
    pub fn emit(&self, emit: &Emit<'_>) -> String {
        let ops = self.ops();
        // The instructions the outputs need, from the last back.
        let mut live = vec![false; ops.len()];
        for &o in self.output_slots() {
            live[o as usize] = true;
        }
        for i in (0..ops.len()).rev() {
            if live[i] {
                for a in operands(ops[i]) {
                    live[a as usize] = true;
                }
            }
        }
        // The temporaries are numbered in the order they are written.
        let mut number = vec![0; ops.len()];
        let mut next = 0;
        for (i, &op) in ops.iter().enumerate() {
            if live[i] && !matches!(op, Op::Input(_) | Op::Const(_)) {
                number[i] = next;
                next += 1;
            }
        }
        let value = |s: u32| -> String {
            match ops[s as usize] {
                Op::Input(k) => (emit.input)(k as usize),
                Op::Const(bits) => literal(emit.language, f64::from_bits(bits)),
                _ => format!("{}{}", emit.temporary, number[s as usize]),
            }
        };
        let mut out = String::new();
        for (i, &op) in ops.iter().enumerate() {
            if !live[i] || matches!(op, Op::Input(_) | Op::Const(_)) {
                continue;
            }
            let rhs = expression(emit.language, op, &value);
            let v = number[i];
            match emit.language {
                Language::C => out.push_str(&format!("{}const double {}{v} = {rhs};\n", emit.indent, emit.temporary)),
                Language::Python => out.push_str(&format!("{}{}{v} = {rhs}\n", emit.indent, emit.temporary)),
            }
        }
        for (k, &o) in self.output_slots().iter().enumerate() {
            let end = if emit.language == Language::C { ";" } else { "" };
            out.push_str(&format!("{}{}[{k}] = {}{end}\n", emit.indent, emit.output, value(o)));
        }
        out
    }
}

/// The slots an instruction reads.
fn operands(op: Op) -> Vec<u32> {
    match op {
        Op::Input(_) | Op::Const(_) => Vec::new(),
        Op::Neg(a) | Op::Recip(a) | Op::Square(a) | Op::Powi(a, _) | Op::Sqrt(a) | Op::Func(_, a) => vec![a],
        Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) | Op::Powf(a, b) | Op::Atan2(a, b) => {
            vec![a, b]
        }
    }
}

/// The right side of an instruction's assignment, its operands written by `value`.
fn expression(language: Language, op: Op, value: &dyn Fn(u32) -> String) -> String {
    let c = language == Language::C;
    match op {
        Op::Input(_) | Op::Const(_) => unreachable!("inputs and constants are written where they are used"),
        Op::Add(a, b) => format!("{} + {}", value(a), value(b)),
        Op::Sub(a, b) => format!("{} - {}", value(a), value(b)),
        Op::Mul(a, b) => format!("{} * {}", value(a), value(b)),
        Op::Div(a, b) => format!("{} / {}", value(a), value(b)),
        Op::Neg(a) => format!("-{}", value(a)),
        Op::Recip(a) => format!("1.0 / {}", value(a)),
        Op::Square(a) => format!("{} * {}", value(a), value(a)),
        Op::Powi(a, n) if c => format!("pow({}, {n}.0)", value(a)),
        Op::Powi(a, n) => format!("np.power({}, {n}.0)", value(a)),
        Op::Powf(a, b) if c => format!("pow({}, {})", value(a), value(b)),
        Op::Powf(a, b) => format!("np.power({}, {})", value(a), value(b)),
        Op::Sqrt(a) if c => format!("sqrt({})", value(a)),
        Op::Sqrt(a) => format!("np.sqrt({})", value(a)),
        Op::Atan2(y, x) if c => format!("atan2({}, {})", value(y), value(x)),
        Op::Atan2(y, x) => format!("np.arctan2({}, {})", value(y), value(x)),
        Op::Func(f, a) => format!("{}({})", function(language, f), value(a)),
    }
}

/// The name of a function in the language's library.
fn function(language: Language, f: Func) -> &'static str {
    match (language, f) {
        (Language::C, Func::Abs) => "fabs",
        (Language::C, f) => f.name(),
        (Language::Python, Func::Sin) => "np.sin",
        (Language::Python, Func::Cos) => "np.cos",
        (Language::Python, Func::Tan) => "np.tan",
        (Language::Python, Func::Asin) => "np.arcsin",
        (Language::Python, Func::Acos) => "np.arccos",
        (Language::Python, Func::Atan) => "np.arctan",
        (Language::Python, Func::Sinh) => "np.sinh",
        (Language::Python, Func::Cosh) => "np.cosh",
        (Language::Python, Func::Tanh) => "np.tanh",
        (Language::Python, Func::Exp) => "np.exp",
        (Language::Python, Func::Log) => "np.log",
        (Language::Python, Func::Abs) => "np.abs",
    }
}

/// A number as a literal that reads back as the same double, in parentheses
/// when negative (so that `x - (-1.5)` stays what it says).
pub fn literal(language: Language, x: f64) -> String {
    let text = if x.is_nan() {
        if language == Language::C { "NAN" } else { "np.nan" }.to_string()
    } else if x.is_infinite() {
        let inf = if language == Language::C { "HUGE_VAL" } else { "np.inf" };
        if x > 0.0 {
            inf.to_string()
        } else {
            format!("-{inf}")
        }
    } else {
        // Rust's `{:?}` is the shortest text that reads back as x, with a
        // decimal point or an exponent: a double literal in C and in Python.
        format!("{x:?}")
    };
    if text.starts_with('-') {
        format!("({text})")
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Pool;
    use std::process::Command;

    /// A tape over x, y, a exercising every instruction, with outputs that
    /// share subexpressions and inputs that some outputs do not use.
    fn tape() -> (Tape, Vec<&'static str>) {
        let texts = vec![
            "a*sin(x)^2 + cos(x)*y - 3*x/y",
            "sqrt(x^2 + y^2) + exp(-x) + log(abs(y) + 1) - tan(x/3)",
            "atan(x) + asin(x/4) + acos(y/4) + sinh(x) + cosh(y) + tanh(a)",
            "x^(-3) + y^7 + x^a + 1/y + atan2(y, x) - 1.5",
            "2.5e-7",
        ];
        let mut pool = Pool::default();
        let roots: Vec<_> = texts.iter().map(|t| pool.parse(t).unwrap()).collect();
        let inputs = [pool.symbol("x"), pool.symbol("y"), pool.symbol("a")];
        (Tape::compile(&pool, &roots, &inputs).unwrap(), texts)
    }

    const POINTS: [[f64; 3]; 3] = [[0.7, 1.3, 2.0], [-0.4, 2.9, 0.5], [1.9, -0.6, -1.25]];

    fn input(k: usize) -> String {
        format!("in[{k}]")
    }

    #[test]
    fn statements_compute_what_the_tape_computes_in_c() {
        let Ok(cc) = crate::c_compiler() else {
            panic!("no C compiler: the tests of the C export need one (cc)");
        };
        let (mut tape, texts) = tape();
        let body =
            tape.emit(&Emit { language: Language::C, input: &input, output: "out", indent: "    ", temporary: "v" });
        let n = texts.len();
        let mut program = String::from("#include <math.h>\n#include <stdio.h>\n\n");
        program.push_str(&format!("static void f(const double *in, double *out) {{\n{body}}}\n\n"));
        program.push_str("int main(void) {\n    static const double points[3][3] = {");
        for p in POINTS {
            program.push_str(&format!("{{{}, {}, {}}}, ", p[0], p[1], p[2]));
        }
        program.push_str(&format!(
            "}};\n    for (int i = 0; i < 3; i++) {{\n        double out[{n}];\n        f(points[i], out);\n        for (int k = 0; k < {n}; k++) printf(\"%.17g\\n\", out[k]);\n    }}\n    return 0;\n}}\n"
        ));
        let dir = std::env::temp_dir().join(format!("lagrange-emit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (source, binary) = (dir.join("f.c"), dir.join("f"));
        std::fs::write(&source, &program).unwrap();
        let built = Command::new(&cc)
            .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-O1", "-o"])
            .arg(&binary)
            .arg(&source)
            .arg("-lm")
            .output()
            .unwrap();
        assert!(built.status.success(), "{}\n{program}", String::from_utf8_lossy(&built.stderr));
        let run = Command::new(&binary).output().unwrap();
        let printed: Vec<f64> = String::from_utf8(run.stdout).unwrap().lines().map(|l| l.parse().unwrap()).collect();
        let _ = std::fs::remove_dir_all(&dir);
        let mut want = vec![0.0; n];
        for (i, p) in POINTS.iter().enumerate() {
            tape.eval(p, &mut want);
            for k in 0..n {
                let got = printed[i * n + k];
                // x^a at x < 0 is NaN in both.
                let same =
                    (got.is_nan() && want[k].is_nan()) || (got - want[k]).abs() <= 1e-13 * want[k].abs().max(1.0);
                assert!(same, "{}: {got} vs {}", texts[k], want[k]);
            }
        }
    }

    #[test]
    fn python_statements_read_like_numpy() {
        let (tape, _) = tape();
        let body =
            tape.emit(&Emit { language: Language::Python, input: &input, output: "out", indent: "", temporary: "v" });
        assert!(body.contains("np.sin(in[0])"), "{body}");
        assert!(body.contains("np.arctan2(in[1], in[0])"), "{body}");
        assert!(body.lines().last().unwrap().starts_with("out[4] = 2.5e-7"), "{body}");
        assert!(!body.contains(';'), "{body}");
    }

    #[test]
    fn literals_read_back_as_the_same_double() {
        for x in [0.1, 1.0, -1.5, 1e-300, 6.02214076e23, f64::MIN_POSITIVE, 1.0 / 3.0] {
            let text = literal(Language::C, x);
            let bare = text.trim_start_matches('(').trim_end_matches(')');
            assert_eq!(bare.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{text}");
        }
        assert_eq!(literal(Language::C, -2.0), "(-2.0)");
        assert_eq!(literal(Language::C, f64::INFINITY), "HUGE_VAL");
        assert_eq!(literal(Language::Python, f64::NEG_INFINITY), "(-np.inf)");
    }
}
