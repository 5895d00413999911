//! Byte mutations of a seed, as blind fuzzers make them (flip, insert a token
//! of the dictionary, delete, duplicate, splice another seed, swap a number for
//! an edge case). Enter with [`mutate`]. The result is made valid UTF-8 (bad
//! bytes become U+FFFD), since every target reads text.

use crate::rng::Rng;

/// Pieces of the expression language and of model files, and values at the
/// edges, inserted whole so that mutants stay close to real input.
pub const DICTIONARY: &[&str] = &[
    "+",
    "-",
    "*",
    "/",
    "^",
    "**",
    "(",
    ")",
    ",",
    "'",
    "''",
    "'''",
    " ",
    "\t",
    "\n",
    "\r\n",
    "x",
    "q'",
    "p_q",
    "t",
    "pi",
    "pi'",
    "sin(",
    "cos(",
    "atan2(",
    "sqrt(",
    "log(",
    "ln(",
    "exp(",
    "abs(",
    "asin(",
    "foo(",
    "0",
    "1",
    "2",
    "-1",
    "0.5",
    ".5",
    "1e",
    "1e-3",
    "1e308",
    "1e-320",
    "1e999",
    "/0",
    "^1000",
    "^-1000",
    "^1001",
    "^0.5",
    "(-1)",
    "(0)",
    "99999999999999999999999999999999999999999",
    "170141183460469231731687303715884105727",
    "é",
    "∂",
    "\u{0}",
    "\"",
    "\"\"\"",
    "'''",
    "\\",
    "\\u00e9",
    "\\n",
    "=",
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "#",
    "coordinates = [\"x\"]\n",
    "coordinates = []\n",
    "lagrangian = \"x'^2/2 - x^2/2\"\n",
    "kinetic = \"",
    "potential = \"",
    "dissipation = \"",
    "gravity = \"g\"\n",
    "gravity = 0\n",
    "[parameters]\n",
    "m = 1.0\n",
    "g = nan\n",
    "g = inf\n",
    "l = -0.0\n",
    "[[particles]]\nmass = \"m\"\nposition = [\"x\", \"y\"]\n",
    "position = [\"x\"]\n",
    "position = []\n",
    "[[constraints]]\nholonomic = \"x^2 - 1\"\n",
    "velocity = \"x'\"\n",
    "name = \"c1\"\n",
    "[forces]\nx = \"-x'\"\n",
    "[initial]\n",
    "\"x'\" = 0\n",
    "x = \"1/0\"\n",
    "[[bodies]]\n",
    "angles = [\"al\", \"be\", \"ga\"]\n",
    "inertia = [\"I\", \"I\", \"I3\"]\n",
    "file = \"cube.toml\"\n",
    "[[parts]]\n",
    "shape = \"box\"\n",
    "shape = \"sphere\"\n",
    "density = \"",
    "size = [\"a\", \"a\", \"a\"]\n",
    "center = [0, 0, 0]\n",
    "orientation = [0, \"pi\", 0]\n",
    "integrand = \"sqrt(1 + y'^2)\"\n",
    "[boundary]\n",
    "start = [0.0, 0.0]\n",
    "end = [1.0, 1e300]\n",
    "lambda_c1",
    "p_x",
    "H",
    "force_",
    "_omega1",
];

/// Numbers to put in place of a number of the seed.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "0.0",
    "1e-300",
    "1e300",
    "1e308",
    "2e308",
    "4.9e-324",
    "nan",
    "inf",
    "-inf",
    "1000",
    "1001",
    "-1000",
    "65",
    "64",
    "1e15",
    "1e16",
    "9007199254740993",
    "9223372036854775808",
    "170141183460469231731687303715884105728",
    "0.1",
    "1/3",
];

/// Longest mutant, in bytes; longer inputs test the size limits, which unit tests cover.
pub const MAX_LEN: usize = 64 * 1024;

/// Mutates `seed` by 1 to 8 random steps; `others` are splice sources.
pub fn mutate(rng: &mut Rng, seed: &str, others: &[&str]) -> String {
    let mut bytes = seed.as_bytes().to_vec();
    let steps = 1 + rng.below(8);
    for _ in 0..steps {
        step(rng, &mut bytes, others);
        bytes.truncate(MAX_LEN);
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

/// One mutation.
fn step(rng: &mut Rng, bytes: &mut Vec<u8>, others: &[&str]) {
    let at = |rng: &mut Rng, len: usize| rng.below(len + 1);
    match rng.below(8) {
        0 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            bytes[i] = rng.next_u64() as u8;
        }
        1 | 2 => {
            let i = at(rng, bytes.len());
            let token = rng.pick(DICTIONARY).as_bytes();
            bytes.splice(i..i, token.iter().copied());
        }
        3 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            let n = 1 + rng.below((bytes.len() - i).min(16));
            bytes.drain(i..i + n);
        }
        4 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            let n = 1 + rng.below((bytes.len() - i).min(64));
            let piece = bytes[i..i + n].to_vec();
            let j = at(rng, bytes.len());
            bytes.splice(j..j, piece);
        }
        5 if !others.is_empty() => {
            let other = rng.pick(others).as_bytes();
            if !other.is_empty() {
                let i = rng.below(other.len());
                let n = 1 + rng.below((other.len() - i).min(256));
                let j = at(rng, bytes.len());
                let k = (j + rng.below(32)).min(bytes.len());
                bytes.splice(j..k, other[i..i + n].iter().copied());
            }
        }
        6 => replace_number(rng, bytes),
        _ => {
            let i = at(rng, bytes.len());
            let token = rng.pick(&["(", ")", "\"", "'", "\n", "^", "-"]).as_bytes();
            bytes.splice(i..i, token.iter().copied());
        }
    }
}

/// Replaces the digits of one number of `bytes` (if any) by an edge value.
fn replace_number(rng: &mut Rng, bytes: &mut Vec<u8>) {
    let starts: Vec<usize> =
        (0..bytes.len()).filter(|&i| bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_digit())).collect();
    if starts.is_empty() {
        return;
    }
    let start = *rng.pick(&starts);
    let end = (start..bytes.len()).find(|&i| !(bytes[i].is_ascii_digit() || bytes[i] == b'.')).unwrap_or(bytes.len());
    bytes.splice(start..end, rng.pick(NUMBERS).bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutants_are_text_bounded_and_differ_from_the_seed() {
        let mut rng = Rng::new(3);
        let seed = "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^2/2\"\n";
        let mut changed = 0;
        for _ in 0..500 {
            let m = mutate(&mut rng, seed, &["[initial]\nx = 1\n"]);
            assert!(m.len() <= MAX_LEN + 3);
            changed += usize::from(m != seed);
        }
        assert!(changed > 450, "only {changed} of 500 mutants changed the seed");
    }
}
