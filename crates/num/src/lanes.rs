//! The per-step work of the Taylor method on `L` trajectories in lock step
//! (`[f64; L]` per coefficient), compiled for the widest vectors the
//! processor has.
//!
//! A Taylor step of an ensemble reads the sizes of the last two orders of its
//! series ([`ratios`]) and sums the whole series by Horner's rule
//! ([`horner`]). Whether every coefficient is finite ([`finite`]) needs a
//! pass over the series only where the state or the ratios say something is
//! off: a non-finite coefficient makes the Horner sum non-finite (a positive
//! step carries an infinity or a NaN through every later order). On a lane
//! array of 8 these loops are one AVX-512 instruction per operation, four
//! with the baseline x86-64 target (SSE2), so the functions here are compiled
//! for AVX-512 and AVX2 as well and choose at run time. The arithmetic is
//! the same on every path (no contraction, the same operations in the same
//! order), so the numbers are too, bit for bit: a lane takes a single run's
//! steps (`taylor_ratio`, [`crate::Taylor`]).

// Calling a function compiled for a processor feature is unsafe; each call
// below checks the feature first.
#![allow(unsafe_code)]

/// The sizes of orders `p − 1` and `p` of `series` (order-major: order `k`
/// of component `i` at `k·dim + i`) relative to its order 0, lane by lane:
/// `max_i |y_i[k]| / max(|y_i|, floor)` (see [`crate::taylor_ratio`]).
pub fn ratios<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, floor: f64) -> ([f64; L], [f64; L]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the processor has AVX-512F, the one feature enabled.
            return unsafe { ratios_avx512(series, dim, p, floor) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, the one feature enabled.
            return unsafe { ratios_avx2(series, dim, p, floor) };
        }
    }
    ratios_lanes(series, dim, p, floor)
}

/// Whether every coefficient of orders `0..=p` of lane `lane` is finite.
pub fn finite<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, lane: usize) -> bool {
    series[..(p + 1) * dim].iter().all(|c| c[lane].is_finite())
}

/// `y_i = Σ_k series[k·dim + i] h^k` lane by lane, by Horner's rule
/// (`acc·h + c`, two roundings per order); `h = 0` gives order 0.
pub fn horner<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, h: &[f64; L], y: &mut [[f64; L]]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: as in `ratios`.
            return unsafe { horner_avx512(series, dim, p, h, y) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: as in `ratios`.
            return unsafe { horner_avx2(series, dim, p, h, y) };
        }
    }
    horner_lanes(series, dim, p, h, y)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn ratios_avx512<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, floor: f64) -> ([f64; L], [f64; L]) {
    ratios_lanes(series, dim, p, floor)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn ratios_avx2<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, floor: f64) -> ([f64; L], [f64; L]) {
    ratios_lanes(series, dim, p, floor)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn horner_avx512<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, h: &[f64; L], y: &mut [[f64; L]]) {
    horner_lanes(series, dim, p, h, y)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn horner_avx2<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, h: &[f64; L], y: &mut [[f64; L]]) {
    horner_lanes(series, dim, p, h, y)
}

#[inline(always)]
fn ratios_lanes<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, floor: f64) -> ([f64; L], [f64; L]) {
    (ratio(series, dim, p - 1, floor), ratio(series, dim, p, floor))
}

/// `max_i |series[k·dim + i]| / max(|series[i]|, floor)` lane by lane.
#[inline(always)]
fn ratio<const L: usize>(series: &[[f64; L]], dim: usize, k: usize, floor: f64) -> [f64; L] {
    let mut m = [0.0f64; L];
    for (c, y) in series[k * dim..(k + 1) * dim].iter().zip(&series[..dim]) {
        for l in 0..L {
            m[l] = m[l].max(c[l].abs() / y[l].abs().max(floor));
        }
    }
    m
}

#[inline(always)]
fn horner_lanes<const L: usize>(series: &[[f64; L]], dim: usize, p: usize, h: &[f64; L], y: &mut [[f64; L]]) {
    for i in 0..dim {
        let mut acc = series[p * dim + i];
        for k in (0..p).rev() {
            let c = &series[k * dim + i];
            for l in 0..L {
                acc[l] = acc[l] * h[l] + c[l];
            }
        }
        y[i] = acc;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_path_gives_the_same_bits() {
        let (dim, p) = (3, 5);
        let series: Vec<[f64; 8]> = (0..(p + 1) * dim)
            .map(|i| std::array::from_fn(|l| ((i * 7 + l * 3) as f64).sin() / (1 + i) as f64))
            .collect();
        let h = std::array::from_fn(|l| 0.01 * l as f64);
        let (mut a, mut b) = (vec![[0.0; 8]; dim], vec![[0.0; 8]; dim]);
        horner(&series, dim, p, &h, &mut a);
        horner_lanes(&series, dim, p, &h, &mut b);
        assert_eq!(a, b);
        assert_eq!(ratios(&series, dim, p, 1e-3), ratios_lanes(&series, dim, p, 1e-3));
        let lane = |l: usize, k: usize| -> f64 {
            (0..dim).map(|i| series[k * dim + i][l].abs() / series[i][l].abs().max(1e-3)).fold(0.0, f64::max)
        };
        let (before_last, last) = ratios(&series, dim, p, 1e-3);
        assert_eq!(before_last[5], lane(5, p - 1));
        assert_eq!(last[7], lane(7, p));
        // One lane's Horner sum is the sum of its series.
        let want: f64 = (0..=p).map(|k| series[k * dim + 1][2] * h[2].powi(k as i32)).sum();
        assert!((a[1][2] - want).abs() < 1e-15);
    }

    #[test]
    fn a_lane_with_an_infinite_or_nan_coefficient_is_not_finite() {
        let mut series = vec![[1.0; 4]; 6];
        series[4][1] = f64::INFINITY;
        series[5][3] = f64::NAN;
        let finite: Vec<bool> = (0..4).map(|l| finite(&series, 2, 2, l)).collect();
        assert_eq!(finite, [true, false, true, false]);
        assert_eq!(ratios(&series, 2, 2, 1e-3).1[0], 1.0);
    }
}
