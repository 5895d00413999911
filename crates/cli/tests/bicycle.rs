//! The benchmark bicycle (Meijaard, Papadopoulos, Ruina and Schwab, Proc. R.
//! Soc. A 463 (2007) 1955–1982), `examples/bicycle/benchmark_bicycle.toml`:
//! four bodies in a tree, two rolling wheels, linearized about upright
//! straight running at speed v. Its roll and steer rows of A must be the
//! paper's linear equations M q'' + v C1 q' + (g K0 + v² K2) q = 0 with the
//! paper's published M, C1, K0 and K2; its eigenvalues at v = 5 those of the
//! paper's table; and the weave and capsize speeds the paper's 4.292382 and
//! 6.024262 m/s.

use crate::common::json;
use serde_json::Value;

const MODEL: &str = "examples/bicycle/benchmark_bicycle.toml";

/// The coefficient matrices M, C1, K0 and K2 for q = (roll, steer) that the
/// paper publishes for its benchmark parameters.
const M: [[f64; 2]; 2] = [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]];
const C1: [[f64; 2]; 2] = [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]];
const K0: [[f64; 2]; 2] = [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]];
const K2: [[f64; 2]; 2] = [[0.0, 76.59734589573222], [0.0, 2.65431523794604]];

/// The paper's A for x = (roll, steer, roll', steer'): the lower rows −M⁻¹(g K0 + v² K2), −M⁻¹ v C1.
fn paper_rows(v: f64) -> [[f64; 4]; 2] {
    let det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    let inv = [[M[1][1] / det, -M[0][1] / det], [-M[1][0] / det, M[0][0] / det]];
    let mut rows = [[0.0; 4]; 2];
    for i in 0..2 {
        for j in 0..2 {
            let (mut k, mut c) = (0.0, 0.0);
            for l in 0..2 {
                k += inv[i][l] * (9.81 * K0[l][j] + v * v * K2[l][j]);
                c += inv[i][l] * v * C1[l][j];
            }
            rows[i][j] = -k;
            rows[i][2 + j] = -c;
        }
    }
    rows
}

/// `lagrange linearize` of the bicycle at each speed, the runs side by side.
fn linearize(speeds: &[f64]) -> Vec<Value> {
    let handles: Vec<_> = speeds
        .iter()
        .map(|&v| {
            std::thread::spawn(move || {
                let set = format!("v={v}");
                json(&["linearize", MODEL, "--about", "steady", "--set", &set, "--format", "json"])
            })
        })
        .collect();
    handles.into_iter().map(|h| h.join().expect("the run")).collect()
}

/// The eigenvalues that are not the cyclic coordinates' zeros, as (re, im).
fn moving(out: &Value) -> Vec<(f64, f64)> {
    out["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e["re"].as_f64().unwrap(), e["im"].as_f64().unwrap()))
        .filter(|(re, im)| re.abs() + im.abs() > 1e-9)
        .collect()
}

#[test]
fn the_benchmark_bicycle_has_the_published_eigenvalues_weave_and_capsize_speeds() {
    let outs = linearize(&[5.0, 4.29, 4.30, 6.02, 6.03]);
    // The roll and steer rows of A at v = 5 against the paper's equations.
    let at5 = &outs[0];
    let state: Vec<&str> = at5["state"].as_array().unwrap().iter().map(|s| s.as_str().unwrap()).collect();
    let col = |name: &str| state.iter().position(|s| *s == name).unwrap_or_else(|| panic!("{name} in {state:?}"));
    let cols = [col("phi"), col("delta"), col("phi'"), col("delta'")];
    let want = paper_rows(5.0);
    for (i, row) in [col("phi'"), col("delta'")].into_iter().enumerate() {
        for (j, &c) in cols.iter().enumerate() {
            let got = at5["A"][row][c].as_f64().unwrap();
            assert!(
                (got - want[i][j]).abs() < 1e-9 * (1.0 + want[i][j].abs()),
                "A[{i}][{j}] = {got}, paper {}",
                want[i][j]
            );
        }
    }
    // Table 2 of the paper at v = 5: castering, weave, capsize.
    let mut got = moving(at5);
    got.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let table = [
        (-14.0783896927982, 0.0),
        (-0.775341882195845, -4.46486771378823),
        (-0.775341882195845, 4.46486771378823),
        (-0.322866429004087, 0.0),
    ];
    assert_eq!(got.len(), 4, "{got:?}");
    for (g, w) in got.iter().zip(table) {
        assert!((g.0 - w.0).abs() < 1e-9 && (g.1 - w.1).abs() < 1e-9, "{g:?} vs the paper's {w:?}");
    }
    // Weave: the oscillating pair's real part changes sign between 4.29 and 4.30;
    // capsize: the slow real root's, between 6.02 and 6.03. Linear interpolation
    // of the crossing lands within 1e-4 of the paper's speeds.
    let weave = |o: &Value| moving(o).into_iter().find(|e| e.1 > 0.0).unwrap().0;
    let capsize = |o: &Value| moving(o).into_iter().filter(|e| e.1 == 0.0).map(|e| e.0).fold(f64::MIN, f64::max);
    let crossing = |v0: f64, v1: f64, a: f64, b: f64| v0 + (v1 - v0) * a / (a - b);
    let (w0, w1) = (weave(&outs[1]), weave(&outs[2]));
    assert!(w0 > 0.0 && w1 < 0.0, "weave {w0} at 4.29, {w1} at 4.30");
    let vw = crossing(4.29, 4.30, w0, w1);
    assert!((vw - 4.292382).abs() < 1e-4, "weave speed {vw}");
    let (c0, c1) = (capsize(&outs[3]), capsize(&outs[4]));
    assert!(c0 < 0.0 && c1 > 0.0, "capsize {c0} at 6.02, {c1} at 6.03");
    let vc = crossing(6.02, 6.03, c0, c1);
    assert!((vc - 6.024262).abs() < 1e-4, "capsize speed {vc}");
}
