//! The human formats of `derive`: text that reads like the lecture notes,
//! LaTeX, and MathML in HTML for the report. (JSON is the `mech::DeriveReport`
//! serialized as it is.)
//!
//! Enter with [`text`], [`latex`] or [`mathml`]. One walk over the derivation
//! ([`layout`]) decides what is shown and in which order, as a sequence of
//! [`Item`]s; the three renderings ([`Text`], [`Latex`], [`MathMl`], one file
//! each in `derive/`) write each item their way, or not at all: LaTeX gives the
//! equations, the text and the MathML also the verdicts and their reasons.
//!
//! A large derivation ([`mech::prints_shared`], the same decision as its
//! JSON's) is written with named intermediates: each rendering runs once to
//! list the expressions it prints, [`sym::Pool::share`] names the
//! subexpressions they would repeat, and the second run writes those as
//! `w1`, `w2`, … and ends with their definitions (a `where` section, a last
//! `align*` block, a last table).

mod latex;
mod mathml;
mod text;

use latex::Latex;
use mathml::{MathMl, Outline};
use mech::{BodyMotion, Constraint, Derivation};
use sym::{ExprId, Printout};
use text::Text;

/// How the renderings of `d` write expressions: as trees when `d` is small;
/// otherwise with the nodes named that the roots `list` prints (given a
/// listing printout, it renders and hands the printout back) would repeat.
fn printout(d: &Derivation, list: impl FnOnce(Printout) -> Printout) -> Printout {
    if !mech::prints_shared(d) {
        return Printout::Trees;
    }
    let roots = list(Printout::roots()).into_roots();
    Printout::Named(d.pool().share(&roots))
}

/// The derivation as text, with the notes' names and the reasons behind each verdict.
pub fn text(d: &Derivation) -> String {
    let render = |out: Printout| {
        let mut r = Text { d, names: d.coordinate_names(), o: String::new(), out };
        layout(d, &mut |item| r.item(item));
        r
    };
    let out = printout(d, |out| render(out).out);
    render(out).finish()
}

/// The derivation as LaTeX (an `align*` environment per section).
pub fn latex(d: &Derivation) -> String {
    let render = |out: Printout| {
        let q = d.q().iter().map(|&q| d.pool().latex(q).to_string()).collect();
        let mut r = Latex { d, q, o: String::new(), blocks: Default::default(), out };
        layout(d, &mut |item| r.item(item));
        r
    };
    let out = printout(d, |out| render(out).out);
    render(out).finish()
}

/// The derivation as an HTML fragment, `<section class="derivation">`: a
/// heading (`<h3>`) per section, each group of equations one
/// `<math display="block">` table, and the verdicts and their reasons as
/// paragraphs. It holds no entity but XML's, so it is also well-formed XML.
pub fn mathml(d: &Derivation) -> String {
    let render = |out: Printout| {
        let mut r = MathMl::new(d, out, None);
        layout(d, &mut |item| r.item(item));
        r
    };
    let out = printout(d, |out| render(out).out);
    render(out).finish()
}

/// The derivation as [`mathml`] writes it when that takes at most `budget`
/// bytes as `size` counts them (a page may escape it); otherwise its outline:
/// the model, the cyclic coordinates and the verdicts with their reasons,
/// without the expressions, and a paragraph
/// saying what was left out and that `lagrange derive` prints it. A page that
/// must open quickly (the report) cannot hold a large mechanism's equations:
/// a chain of 50 rods takes 20 MB of MathML, most of it named intermediates.
pub fn mathml_within(d: &Derivation, budget: usize, size: impl Fn(&str) -> usize) -> String {
    let whole = mathml(d);
    let bytes = size(&whole);
    if bytes <= budget {
        return whole;
    }
    let mut r = MathMl::new(d, Printout::Trees, Some(Outline { whole: bytes, budget }));
    layout(d, &mut |item| r.item(item));
    r.finish()
}

/// One thing the layout puts down.
enum Item<'a> {
    /// The model's name, its coordinates (and constraints) and parameters.
    Title,
    /// An expression the model defines: T, U, L or R.
    Define(Defined, ExprId),
    /// The generalized force on coordinate `i`, when it is not zero.
    Force(usize, ExprId),
    /// The inputs u, their values in runs, and B = ∂f/∂u.
    Inputs,
    /// A rigid body's angular velocity and momentum.
    Body(&'a BodyMotion),
    /// The start of a section.
    Heading(Section),
    /// The momentum of coordinate `i`.
    Momentum(usize, ExprId),
    /// The equation of motion `E_i = 0` of coordinate `i`.
    Equation(usize, ExprId),
    /// The equations as `M q'' = f`.
    MassMatrixForm,
    /// One constraint.
    Constraint(&'a Constraint),
    /// What the constraints imply together.
    ConstraintNotes,
    /// The equation with multipliers of coordinate `i`.
    MultiplierEquation(usize, ExprId),
    /// How q'' and λ are found, and the constraint forces.
    ConstraintForces,
    /// One impact: its surface, ∇φ and v_n.
    Impact(&'a mech::ImpactLaw),
    /// The cyclic coordinates and what they conserve.
    Cyclic,
    /// The conserved quantities of symmetries of L (Noether), when there are any.
    Symmetries,
    /// H, or why it has no closed form.
    Hamiltonian(Option<ExprId>),
    /// Whether H is the energy and whether it is conserved, with the reasons.
    Verdicts,
    /// Hamilton's equations of coordinate `i`: `q' = dq`, `p' = dp`.
    HamiltonEquation(usize, ExprId, ExprId),
}

/// The expressions a model defines.
#[derive(Clone, Copy)]
enum Defined {
    Kinetic,
    Potential,
    Lagrangian,
    Dissipation,
}

/// The sections, in the order the layout gives them.
#[derive(Clone, Copy)]
enum Section {
    Momenta,
    Equations,
    Constraints,
    Multipliers,
    Impacts,
    Hamiltonian,
    Hamilton,
}

/// Walks the derivation in order, handing each item to `emit`.
fn layout<'a>(d: &'a Derivation, emit: &mut impl FnMut(Item<'a>)) {
    let pool = d.pool();
    emit(Item::Title);
    if let Some(t) = d.kinetic() {
        emit(Item::Define(Defined::Kinetic, t));
    }
    if let Some(u) = d.potential() {
        emit(Item::Define(Defined::Potential, u));
    }
    emit(Item::Define(Defined::Lagrangian, d.lagrangian()));
    if let Some(r) = d.dissipation() {
        emit(Item::Define(Defined::Dissipation, r));
    }
    for (i, &f) in d.forces().iter().enumerate() {
        if !pool.is_zero(f) {
            emit(Item::Force(i, f));
        }
    }
    if !d.inputs().is_empty() {
        emit(Item::Inputs);
    }
    for b in d.bodies() {
        emit(Item::Body(b));
    }
    emit(Item::Heading(Section::Momenta));
    for (i, &p) in d.momenta().iter().enumerate() {
        emit(Item::Momentum(i, p));
    }
    emit(Item::Heading(Section::Equations));
    for (i, &e) in d.equations().iter().enumerate() {
        emit(Item::Equation(i, e));
    }
    emit(Item::MassMatrixForm);
    if !d.constraints().is_empty() {
        emit(Item::Heading(Section::Constraints));
        for c in &d.constraints().list {
            emit(Item::Constraint(c));
        }
        emit(Item::ConstraintNotes);
        emit(Item::Heading(Section::Multipliers));
        for (i, &e) in d.constraints().multiplier_equations.iter().enumerate() {
            emit(Item::MultiplierEquation(i, e));
        }
        emit(Item::ConstraintForces);
    }
    if !d.impacts().is_empty() {
        emit(Item::Heading(Section::Impacts));
        for i in d.impacts() {
            emit(Item::Impact(i));
        }
    }
    emit(Item::Cyclic);
    if symmetries(d).next().is_some() {
        emit(Item::Symmetries);
    }
    emit(Item::Heading(Section::Hamiltonian));
    emit(Item::Hamiltonian(d.hamiltonian()));
    emit(Item::Verdicts);
    if let Some(eqs) = &d.hamilton() {
        emit(Item::Heading(Section::Hamilton));
        for (i, &(dq, dp)) in eqs.iter().enumerate() {
            emit(Item::HamiltonEquation(i, dq, dp));
        }
    }
}

/// The conserved quantities found from symmetries of L (Noether).
fn symmetries(d: &Derivation) -> impl Iterator<Item = &mech::Conserved> {
    d.conserved().iter().filter(|c| matches!(c.reason, mech::ConservedReason::Symmetry { .. }))
}

/// "" for one, "s" otherwise.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
/// The tags of a constraint: its kind, whether it depends on time, and for a
/// velocity constraint whether it is integrable.
fn constraint_tags(c: &Constraint) -> Vec<&'static str> {
    let tags = [
        Some(c.kind.name()),
        Some(match c.rheonomic {
            Some(true) => "rheonomic",
            Some(false) => "scleronomic",
            None => "time dependence undecided",
        }),
        match (c.kind, c.integrable) {
            (mech::ConstraintKind::Velocity, Some(true)) => Some("integrable"),
            (mech::ConstraintKind::Velocity, Some(false)) => Some("not integrable"),
            (mech::ConstraintKind::Velocity, None) => Some("integrability undecided"),
            _ => None,
        },
    ];
    tags.into_iter().flatten().collect()
}

/// Whether H is the energy, as a sentence without its reasons.
fn energy_verdict(d: &Derivation) -> &'static str {
    match d.hamiltonian_is_energy() {
        Some(true) => "H is the energy",
        Some(false) => "H is not the energy",
        None => "whether H is the energy is not known",
    }
}

/// Whether H is conserved, as a sentence without its reasons.
fn conservation_verdict(d: &Derivation) -> &'static str {
    if d.hamiltonian_conserved() {
        "H is conserved"
    } else {
        "H is not conserved"
    }
}

/// What becomes of the momentum of cyclic coordinate `i`: conserved, or why not.
fn cyclic_momentum(d: &Derivation, names: &[&str], i: usize) -> &'static str {
    let pool = d.pool();
    if d.conserved().iter().any(|c| c.name == format!("p_{}", names[i])) {
        "is conserved"
    } else if d.constraints().list.iter().any(|c| !pool.is_zero(c.jacobian[i])) {
        "would be conserved, but a constraint force acts on it"
    } else if d
        .verdicts()
        .cyclic
        .iter()
        .any(|r| matches!(r, mech::CyclicReason::MomentumUndecided { coordinate } if *coordinate == names[i]))
    {
        "would be conserved, but whether dissipation or a force acts on it is not known"
    } else {
        "would be conserved, but dissipation or a force acts on it"
    }
}

#[cfg(test)]
mod tests {
    use super::{latex, mathml, mathml_within, text};

    /// A pendulum: one coordinate, no cyclic one, H the energy.
    const PENDULUM: &str = r#"
name = "pendulum"
coordinates = ["th"]
gravity = "g"
[parameters]
m = 2.0
g = 9.81
[[particles]]
mass = "m"
position = ["sin(th)", "-cos(th)"]
"#;

    /// A free particle in the plane in polar coordinates: th is cyclic.
    const FREE: &str = r#"
name = "free particle"
coordinates = ["r", "th"]
[[particles]]
mass = "1"
position = ["r*cos(th)", "r*sin(th)"]
"#;

    fn derive(text: &str) -> mech::Derivation {
        mech::Derivation::new(mech::Model::parse(text, &[]).expect("the model parses")).expect("it derives")
    }

    #[track_caller]
    fn check_contains(output: &str, expect: &[&str]) {
        for line in expect {
            assert!(output.contains(line), "{line:?} is missing from\n{output}");
        }
    }

    #[test]
    fn text_reads_like_the_notes() {
        let out = text(&derive(PENDULUM));
        assert!(out.starts_with("pendulum\n1 degree of freedom: th\nparameters: m = 2, g = 9.81\n"), "{out}");
        check_contains(
            &out,
            &[
                "generalized momenta p_q = ∂L/∂q'",
                "  p_th = m*th'",
                "cyclic coordinates\n  none: L depends on every coordinate",
                "  H is the energy:",
                "Hamilton's equations",
            ],
        );
        let out = text(&derive(FREE));
        check_contains(&out, &["2 degrees of freedom: r, th", "  th: ∂L/∂th = 0, so p_th = ", "is conserved"]);
    }

    #[test]
    fn latex_gives_the_equations_in_blocks() {
        let out = latex(&derive(PENDULUM));
        assert!(out.starts_with("% pendulum (lagrange derive --format latex)\n\\begin{align*}\n"), "{out}");
        assert_eq!(out.matches("\\begin{align*}").count(), 2, "main and Hamilton blocks: {out}");
        assert_eq!(out.matches("\\begin{align*}").count(), out.matches("\\end{align*}").count());
        check_contains(&out, &["% equation of motion for $\\theta$", "H &= "]);
        // A line break in the model's name would end the comment and run the rest as LaTeX.
        let out = latex(&derive(&PENDULUM.replace("name = \"pendulum\"", "name = \"a\\n\\\\input{x}\"")));
        assert!(out.starts_with("% a \\input{x} (lagrange derive --format latex)\n"), "{out}");
    }

    /// The block `<math>` elements of a fragment, as text.
    fn blocks(html: &str) -> Vec<&str> {
        html.split("<math display=\"block\">").skip(1).map(|b| b.split("</math>").next().unwrap_or(b)).collect()
    }

    /// Checks that the fragment of `d` is well-formed, a section with no text
    /// outside its children, and that every equation the derivation holds is
    /// set in a block `<math>`.
    #[track_caller]
    fn check_mathml(d: &mech::Derivation) -> String {
        let out = mathml(d);
        let doc = roxmltree::Document::parse(&out).unwrap_or_else(|e| panic!("{e}: not well-formed:\n{out}"));
        let section = doc.root_element();
        assert_eq!((section.tag_name().name(), section.attribute("class")), ("section", Some("derivation")));
        let blocks = blocks(&out);
        let pool = d.pool();
        let mut equations: Vec<sym::ExprId> = d.momenta().to_vec();
        equations.extend(d.equations());
        equations.extend(d.forcing());
        equations.extend(d.hamiltonian());
        equations.extend(d.constraints().list.iter().map(|c| c.expr));
        equations.extend(d.hamilton().unwrap_or_default().iter().flat_map(|&(dq, dp)| [dq, dp]));
        for e in equations {
            let m = pool.mathml(e).to_string();
            assert!(blocks.iter().any(|b| b.contains(&m)), "{} is in no block of\n{out}", pool.display(e));
        }
        out
    }

    #[test]
    fn a_derivation_past_the_budget_is_outlined_with_its_verdicts() {
        let d = derive(FREE);
        let whole = mathml(&d);
        assert_eq!(mathml_within(&d, whole.len(), str::len), whole);
        let outline = mathml_within(&d, whole.len() - 1, str::len);
        let doc = roxmltree::Document::parse(&outline).unwrap_or_else(|e| panic!("{e}: not well-formed:\n{outline}"));
        assert_eq!(doc.root_element().attribute("class"), Some("derivation"));
        // No equation, and a pointer to where they are.
        assert!(!outline.contains("<math display=\"block\">"), "{outline}");
        assert!(outline.contains("<code>lagrange derive</code> prints them all"), "{outline}");
        // The cyclic coordinate, with its momentum named, not written out.
        check_contains(&outline, &["Cyclic coordinates", "is conserved", "H is the energy", "Hamiltonian"]);
        assert!(!outline.contains(&d.pool().mathml(d.momenta()[1]).to_string()), "{outline}");
    }

    #[test]
    fn mathml_sets_the_equations_and_says_the_verdicts() {
        let d = derive(PENDULUM);
        let out = check_mathml(&d);
        let doc = roxmltree::Document::parse(&out).expect("well-formed");
        let headings: Vec<String> = doc
            .descendants()
            .filter(|n| n.has_tag_name("h3"))
            .map(|h| h.children().find(|c| c.is_text()).and_then(|t| t.text()).unwrap_or_default().trim().to_string())
            .collect();
        assert_eq!(
            headings,
            [
                "Lagrangian",
                "Generalized momenta",
                "Euler–Lagrange equations",
                "In the form",
                "Cyclic coordinates",
                "Hamiltonian",
                "Hamilton’s equations"
            ]
        );
        // T, U, L; the momentum; the equation of motion; M q'' = f; H and T + U; Hamilton's equations.
        assert_eq!(blocks(&out).len(), 6, "{out}");
        check_contains(
            &out,
            &[
                "<p><strong>pendulum</strong>: 1 degree of freedom: <math><mi>θ</mi></math></p>",
                "<p>None: L depends on every coordinate.</p>",
                "<p>H is the energy:</p>",
                "<p>H is conserved:</p>",
                "<mtext>for&#xA0;</mtext><mi>θ</mi>",
            ],
        );
        for reason in d
            .verdicts()
            .energy
            .iter()
            .map(ToString::to_string)
            .chain(d.verdicts().conservation.iter().map(ToString::to_string))
        {
            check_contains(&out, &[&format!("<li>{}</li>", crate::markup::text(&reason.to_string()))]);
        }

        let out = check_mathml(&derive(FREE));
        check_contains(&out, &["<p><math><mi>θ</mi></math>: <math>", "</math> is conserved.</p>"]);
        // The model's name is text, not markup.
        let out = check_mathml(&derive(&PENDULUM.replace("name = \"pendulum\"", "name = \"<b>&</b>\"")));
        check_contains(&out, &["<strong>&lt;b&gt;&amp;&lt;/b&gt;</strong>"]);
    }

    /// The benchmark bicycle, the one example large enough to print with named intermediates.
    const BICYCLE: &str = include_str!("../../../examples/bicycle/benchmark_bicycle.toml");

    /// The names `w1`, `w2`, … a text uses, each once, in order.
    fn names_in(text: &str) -> Vec<usize> {
        let mut names: Vec<usize> = text
            .split(|c: char| !c.is_ascii_alphanumeric())
            .filter_map(|word| word.strip_prefix('w')?.parse().ok())
            .collect();
        names.sort_unstable();
        names.dedup();
        names
    }

    /// The bicycle's text (1.5 MB as trees), LaTeX and MathML name each
    /// shared subexpression once and define every name they use, in a last
    /// section, each definition using only the names before it.
    #[test]
    fn a_large_derivation_prints_each_shared_subexpression_once() {
        let d = derive(BICYCLE);
        let out = text(&d);
        assert!(out.len() < 1_000_000, "{} bytes", out.len());
        let (body, defs) = out.split_once("\nwhere\n").expect("a where section");
        let mut defined = Vec::new();
        for line in defs.lines() {
            let (name, expr) = line.trim_start().split_once(" = ").expect("name = expr");
            for k in names_in(expr) {
                assert!(defined.contains(&k), "{name} uses w{k} before its definition");
            }
            defined.extend(names_in(name));
        }
        let used = names_in(body);
        assert!(used.len() > 100, "{} names used", used.len());
        for k in used {
            assert!(defined.contains(&k), "w{k} is used and not defined");
        }
        let out = latex(&d);
        let (_, block) = out.rsplit_once("\\begin{align*}").expect("blocks");
        assert!(block.starts_with("\nw_{1} &= ") && block.contains("  % where"), "{}", &block[..200]);
        let out = mathml(&d);
        roxmltree::Document::parse(&out).unwrap_or_else(|e| panic!("{e}: not well-formed"));
        let (_, last) = out.rsplit_once("<h3>Where</h3>").expect("a last table");
        assert!(last.contains("<msub><mi>w</mi><mn>1</mn></msub></mtd>"), "{}", &last[..400]);
    }

    #[test]
    fn mathml_of_every_example_model_is_well_formed() {
        let root = format!("{}/../../examples", env!("CARGO_MANIFEST_DIR"));
        let mut seen = 0;
        for dir in ["", "/tops", "/constraints"] {
            let dir = format!("{root}{dir}");
            let mut paths: Vec<_> = std::fs::read_dir(&dir)
                .expect("the examples are there")
                .map(|e| e.expect("a directory entry").path())
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect();
            paths.sort();
            for path in paths {
                let text = std::fs::read_to_string(&path).expect("readable");
                if !text.lines().any(|l| l.starts_with("coordinates")) {
                    continue; // a body file, which a model names
                }
                let read = |name: &str| std::fs::read_to_string(format!("{dir}/{name}")).map_err(|e| e.to_string());
                let model = mech::Model::parse_with(&text, &[], &read)
                    .unwrap_or_else(|e| panic!("{}: {}", path.display(), e.message));
                let d = mech::Derivation::new(model).expect("it derives");
                check_mathml(&d);
                seen += 1;
            }
        }
        assert!(seen >= 20, "only {seen} example models");
    }
}
