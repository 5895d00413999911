//! Stop events through the library's API: located to the accuracy of the
//! steps and audited like every row.

mod common;

use common::{derive, PENDULUM};
use mech::{Method, RunConfig, StopCondition};
use std::ops::ControlFlow;

#[test]
fn a_stop_event_is_as_accurate_as_the_steps_and_audited_like_every_row() {
    // A swing of one radian: at the bottom, th'² = 2 g/l (1 − cos 1) by energy.
    let d = derive(&PENDULUM.replace("th = 0.01", "th = 1.0"));
    let stop = StopCondition::parse(&d, "th < 0", "the stop condition").unwrap();
    let run = |method: Option<Method>, rtol: f64| {
        let config = RunConfig { until: 10.0, method, rtol, stop_when: vec![stop.clone()], ..RunConfig::default() };
        mech::simulate(&d, &config, |_| ControlFlow::Continue(())).unwrap()
    };
    let report = run(None, 1e-9);
    assert_eq!(report.method, Method::KahanLi8);
    assert_eq!(report.stopped_by.as_deref(), Some("th < 0"));
    let speed = -(2.0 * 9.81 / 1.5 * (1.0 - 1f64.cos())).sqrt();
    assert!(report.final_q[0].abs() < 1e-12, "{}", report.final_q[0]);
    assert!((report.final_qd[0] / speed - 1.0).abs() < 1e-9, "{} vs {speed}", report.final_qd[0]);
    let h = &report.invariants[0];
    assert!((h.final_value - h.initial).abs() < 1e-9 * h.initial.abs(), "{h:?}");
    assert!(h.max_abs_drift >= (h.final_value - h.initial).abs(), "{h:?}");
    // The time agrees with a run at a far tighter tolerance.
    let reference = run(Some(Method::Dop853), 1e-13);
    assert!((report.t_final - reference.t_final).abs() < 1e-9, "{} vs {}", report.t_final, reference.t_final);
}
