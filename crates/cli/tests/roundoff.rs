//! Round-off left by decimal coefficients must not decide a verdict (issue #29,
//! case 10): 0.1*3 − 0.3 is 5.6e-17 in f64, and a term carrying it made a
//! cyclic coordinate "not cyclic", so its momentum was never audited.

use crate::common::{json, TempFile};

fn model(coefficient: &str) -> TempFile {
    let text = format!(
        "name = \"residue\"\ncoordinates = [\"al\", \"be\"]\nkinetic = \"{coefficient}*sin(al)*al'^2/2 + al'^2/2 + be'^2/2\"\npotential = \"be^2\"\n"
    );
    TempFile::with_text("roundoff", &text)
}

fn cyclic(m: &TempFile) -> Vec<String> {
    let v = json(&["derive", m.path(), "--format", "json"]);
    v["cyclic"].as_array().expect("a list").iter().map(|c| c.as_str().expect("a name").to_string()).collect()
}

#[test]
fn a_coefficient_that_cancels_to_round_off_is_zero_and_the_coordinate_cyclic() {
    for zero in ["(0.1*3 - 0.3)", "(0.1 + 0.2 - 0.3)", "(3/10 - 1/10*3)"] {
        assert_eq!(cyclic(&model(zero)), ["al"], "{zero}");
    }
}

#[test]
fn a_small_coefficient_that_is_not_round_off_keeps_its_term() {
    for small in ["1e-12", "(1.000000000001 - 1)", "(3/10 - 1/10*3 + 1/1000000000000)"] {
        assert!(cyclic(&model(small)).is_empty(), "{small}");
    }
}
