//! `simulate --plot`: the figure of a run knows its model (angles wrapped,
//! particles' paths in the plane, the drift of conserved quantities only).

use crate::common::{ok, scratch};

/// The figure `simulate MODEL --until T --plot` draws.
fn plot(model: &str, until: &str) -> String {
    let name = model.rsplit('/').next().unwrap_or(model).replace(".toml", ".svg");
    let svg = scratch("simulate-plot", &name);
    ok(&["simulate", model, "--until", until, "--plot", svg.to_str().unwrap()]);
    std::fs::read_to_string(&svg).unwrap()
}

#[test]
fn the_plot_follows_the_model() {
    // Two bobs in the plane, angles that go over the top, H conserved.
    let svg = plot("examples/double_pendulum.toml", "20");
    for text in ["Paths in the plane", "particle 2", "angles wrapped to (−π, π]", "a (wrapped)", "Drift of conserved"]
    {
        assert!(svg.contains(text), "the double pendulum's plot lacks {text:?}");
    }

    // Kepler's orbit has no particles; its angle wraps.
    let svg = plot("examples/kepler.toml", "20");
    assert!(!svg.contains("in the plane") && svg.contains("th (wrapped)"));

    // The spherical pendulum's azimuth is cyclic, and still an angle.
    let svg = plot("examples/spherical_pendulum.toml", "30");
    assert!(svg.contains("ph (wrapped)"), "φ is not wrapped");

    // The drive feeds energy in: nothing is conserved, so no drift is drawn.
    let svg = plot("examples/driven_oscillator.toml", "10");
    assert!(!svg.contains("Drift") && svg.contains("Phase portrait of x"));
}
