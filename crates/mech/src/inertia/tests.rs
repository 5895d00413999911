//! Unit tests of the inertia module: the notes' cubes, every shape's standard
//! moments through a whole body file, the parallel-axis theorem, turned parts,
//! exact polynomial densities and the cubature of a Gaussian density.

use super::*;

const CUBE: &str = "name = \"cube\"\n[parameters]\nM = 3.0\na = 2.0\n[[parts]]\nshape = \"box\"\nmass = \"M\"\nsize = [\"a\", \"a\", \"a\"]\ncenter = [\"a/2\", \"a/2\", \"a/2\"]\n";

fn props(source: &str) -> MassProperties {
    BodyFile::parse(source, &[]).unwrap().mass_properties().unwrap()
}

#[track_caller]
fn check_matrix(p: &MassProperties, m: &ExprMatrix, expect: [[&str; 3]; 3]) {
    let got = m.map(|row| row.map(|e| p.pool().display(e).to_string()));
    assert_eq!(got, expect.map(|row| row.map(String::from)));
}

#[track_caller]
fn close(got: f64, want: f64, rel: f64) {
    assert!((got - want).abs() <= rel * want.abs().max(1e-300), "got {got}, want {want}");
}

#[test]
fn notes_cube_about_centre_and_corner() {
    let mut p = props(CUBE);
    let t = p.tensor;
    check_matrix(&p, &t, [["M*a^2/6", "0", "0"], ["0", "M*a^2/6", "0"], ["0", "0", "M*a^2/6"]]);
    let corner = p.parse_about("0,0,0").unwrap();
    let c = p.about(corner);
    check_matrix(
        &p,
        &c,
        [
            ["2*M*a^2/3", "-M*a^2/4", "-M*a^2/4"],
            ["-M*a^2/4", "2*M*a^2/3", "-M*a^2/4"],
            ["-M*a^2/4", "-M*a^2/4", "2*M*a^2/3"],
        ],
    );
    let numeric = p.about_values([0.0; 3]);
    let exact = p.values(&c);
    for j in 0..3 {
        for k in 0..3 {
            close(numeric[j][k], exact[j][k], 1e-14);
        }
    }
    // M a² = 12: about the corner the moments are a²M·(1/6, 11/12, 11/12).
    let pr = principal(&p.values(&c));
    close(pr.moments[0], 2.0, 1e-14);
    close(pr.moments[1], 11.0, 1e-14);
    close(pr.moments[2], 11.0, 1e-14);
    let s = 1.0 / 3f64.sqrt();
    for k in 0..3 {
        close(pr.axes[0][k], s, 1e-12);
    }
    assert_eq!(pr.symmetry, Symmetry::Symmetric);
}

#[test]
fn principal_axes_are_deterministic() {
    let pr = principal(&[[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]]);
    assert_eq!(pr.axes, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    assert_eq!(pr.symmetry, Symmetry::Spherical);
    let pr = principal(&[[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]]);
    assert_eq!(pr.moments, [1.0, 3.0, 3.0]);
    assert_eq!(pr.axes, [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
}

#[test]
fn a_turned_box_keeps_its_principal_moments() {
    let plain = "[[parts]]\nshape = \"box\"\nmass = 2\nsize = [1, 2, 3]\n";
    let turned = format!("{plain}orientation = [0.3, 1.1, -0.7]\n");
    let p0 = props(plain);
    let p1 = props(&turned);
    let i0 = p0.values(&p0.tensor);
    let i1 = p1.values(&p1.tensor);
    // R I Rᵀ with R = Dᵀ.
    let d = crate::euler::rotation_f64(0.3, 1.1, -0.7);
    for j in 0..3 {
        for k in 0..3 {
            let want: f64 = (0..3).map(|a| d[a][j] * i0[a][a] * d[a][k]).sum();
            assert!((i1[j][k] - want).abs() < 1e-13, "{j}{k}: {} vs {want}", i1[j][k]);
        }
    }
    assert!(i1[0][1].abs() > 0.1, "the turn mixes the axes");
    let (a, b) = (principal(&i0), principal(&i1));
    for k in 0..3 {
        close(a.moments[k], b.moments[k], 1e-13);
    }
    // The smallest moment's axis is the box's long edge (part z), i.e. row 2 of D.
    for k in 0..3 {
        close(b.axes[0][k].abs(), d[2][k].abs(), 1e-12);
    }
}

#[test]
fn linear_density_is_exact() {
    // ρ = rho (1 + x/a) on [0,a]×[0,b]×[0,c]: M = 3/2 rho a b c, X = 5a/9, and by hand
    // ∫ρ x² = rho b c (a³/3 + a³/4) = 7/12 rho a³ b c, so I_yy(CM) about y through the CM is
    // ∫ρ (x² + z²) − M (X² + Z²) = rho a b c (7/12 a² + c²/2) − 3/2 rho a b c (25/81 a² + c²/4).
    let src = "[parameters]\nrho = 2.0\na = 1.0\nb = 2.0\nc = 3.0\n[[parts]]\nshape = \"density\"\ndensity = \"rho*(1 + x/a)\"\nregion = [[0, \"a\"], [0, \"b\"], [0, \"c\"]]\n";
    let p = props(src);
    assert!(p.exact);
    assert_eq!(p.pool().display(p.mass).to_string(), "3*a*b*c*rho/2");
    assert_eq!(p.pool().display(p.center_of_mass[0]).to_string(), "5*a/9");
    let (rho, a, b, c) = (2.0, 1.0, 2.0, 3.0);
    let m = 1.5 * rho * a * b * c;
    let iyy = rho * a * b * c * (7.0 / 12.0 * a * a + c * c / 2.0) - m * (25.0 / 81.0 * a * a + c * c / 4.0);
    close(p.value(p.tensor[1][1]), iyy, 1e-14);
    close(p.value(p.tensor[0][1]), 0.0, 1e-14);
}

#[test]
fn gaussian_density_by_cubature() {
    // ρ = exp(−x²) on [−1, 1] × [0, 1] × [0, 1]: M = √π erf(1), ∫x²ρ = (√π erf(1) − 2/e)/2.
    let src = "[[parts]]\nshape = \"density\"\ndensity = \"exp(-x^2)\"\nregion = [[-1, 1], [0, 1], [0, 1]]\n";
    let p = props(src);
    assert!(!p.exact);
    let erf1 = 0.842_700_792_949_714_9_f64;
    let m = std::f64::consts::PI.sqrt() * erf1;
    let x2 = 0.5 * (m - 2.0 / std::f64::consts::E);
    close(p.value(p.mass), m, 1e-10);
    // About the CM (0, 1/2, 1/2): I_xx = ∫ρ((y−½)² + (z−½)²) = M/6.
    close(p.value(p.tensor[0][0]), m / 6.0, 1e-10);
    close(p.value(p.tensor[1][1]), x2 + m / 12.0, 1e-10);
    let cub = p.cubature.unwrap();
    assert!(cub.converged && cub.tensor_error < 1e-8, "{cub:?}");
}

#[test]
fn right_angles_turn_exactly() {
    // A rod (along its part's z) laid on the body's x axis by α = β = π/2.
    let p = props("[parameters]\nm = 1.0\nl = 2.0\n[[parts]]\nshape = \"rod\"\nmass = \"m\"\nsize = [\"l\"]\norientation = [\"pi/2\", \"pi/2\", 0]\n");
    let t = p.tensor;
    check_matrix(&p, &t, [["0", "0", "0"], ["0", "l^2*m/12", "0"], ["0", "0", "l^2*m/12"]]);
    // 30° about z (α = π/6) of a box with edges 1, 2, 3 mixes x and y with sqrt(3).
    let p = props("[[parts]]\nshape = \"box\"\nmass = 12\nsize = [1, 2, 3]\norientation = [\"pi/6\", 0, 0]\n");
    assert!(
        p.pool().display(p.tensor[0][1]).to_string().contains("sqrt(3)")
            || p.pool().display(p.tensor[0][1]).to_string().contains("3^(1/2)"),
        "{}",
        p.pool().display(p.tensor[0][1])
    );
}

#[test]
fn two_masses_give_the_reduced_mass() {
    let src = "[parameters]\nm1 = 1.0\nm2 = 3.0\nl = 2.0\n[[parts]]\nshape = \"point\"\nmass = \"m1\"\n[[parts]]\nshape = \"point\"\nmass = \"m2\"\ncenter = [\"l\", 0, 0]\n";
    let p = props(src);
    assert_eq!(p.pool().display(p.center_of_mass[0]).to_string(), "l*m2/(m1 + m2)");
    assert_eq!(p.pool().display(p.tensor[1][1]).to_string(), "l^2*m1*m2/(m1 + m2)");
    assert!(p.pool().is_zero(p.tensor[0][0]));
    close(p.value(p.tensor[2][2]), 3.0, 1e-15);
}

/// A tensor part given the solid cube's tensor M a²/6 · 1 is the cube: the same
/// mass, centre of mass and tensor, exactly, about the centre and a corner.
#[test]
fn a_given_tensor_equal_to_a_cube_is_the_cube() {
    let given = "name = \"cube\"\n[parameters]\nM = 3.0\na = 2.0\n[[parts]]\nshape = \"tensor\"\nmass = \"M\"\ninertia = [[\"M*a^2/6\", 0, 0], [0, \"M*a^2/6\", 0], [0, 0, \"M*a^2/6\"]]\ncenter = [\"a/2\", \"a/2\", \"a/2\"]\n";
    let principal_form = given.replace(
        "inertia = [[\"M*a^2/6\", 0, 0], [0, \"M*a^2/6\", 0], [0, 0, \"M*a^2/6\"]]",
        "inertia = [\"M*a^2/6\", \"M*a^2/6\", \"M*a^2/6\"]",
    );
    let mut cube = props(CUBE);
    let corner = cube.parse_about("0,0,0").unwrap();
    let want = cube.about(corner);
    let want_text = want.map(|row| row.map(|e| cube.pool().display(e).to_string()));
    for src in [given, principal_form.as_str()] {
        let mut p = props(src);
        assert!(p.exact);
        assert_eq!(p.parts[0].shape, "tensor");
        assert_eq!(p.parts[0].method, "given");
        assert_eq!(p.pool().display(p.mass).to_string(), "M");
        let t = p.tensor;
        check_matrix(&p, &t, [["M*a^2/6", "0", "0"], ["0", "M*a^2/6", "0"], ["0", "0", "M*a^2/6"]]);
        let corner = p.parse_about("0,0,0").unwrap();
        let c = p.about(corner);
        assert_eq!(c.map(|row| row.map(|e| p.pool().display(e).to_string())), want_text);
    }
}

/// A given tensor turned by Euler angles is R I Rᵀ, like a shape.
#[test]
fn a_given_tensor_turns_like_a_shape() {
    let boxed = "[[parts]]\nshape = \"box\"\nmass = 2\nsize = [1, 2, 3]\norientation = [0.3, 1.1, -0.7]\n";
    // The box's moments 2·(b² + c²)/12, …: (13/6, 5/3, 5/6).
    let given = "[[parts]]\nshape = \"tensor\"\nmass = 2\ninertia = [\"13/6\", \"5/3\", \"5/6\"]\norientation = [0.3, 1.1, -0.7]\n";
    let (a, b) = (props(boxed), props(given));
    let (ia, ib) = (a.values(&a.tensor), b.values(&b.tensor));
    for j in 0..3 {
        for k in 0..3 {
            assert!((ia[j][k] - ib[j][k]).abs() < 1e-14, "{j}{k}: {} vs {}", ia[j][k], ib[j][k]);
        }
    }
}
