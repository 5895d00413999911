//! `lagrange modes`: small oscillations about an equilibrium — the equilibrium,
//! T and U, the secular equation, the normal frequencies and mode shapes — as
//! text that follows the notes' Sec. 3.3, as JSON (`lagrange.modes/1`), and as
//! an animated SVG of every mode (`--animate`).
//!
//! The computation is `mech::normal_modes`; this module renders it. An unstable
//! equilibrium is bad input (exit 2) unless `--allow-unstable` asks to see it.

use crate::diagnostics::Failure;
use crate::output::{human, ReportFormat};
use mech::{Derivation, ModeKind, Modes, ModesConfig};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Options of `modes`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML).
    pub model: PathBuf,
    /// Start the search for the equilibrium here instead of at [initial]: --at a=0 b=0.
    #[arg(long = "at", value_name = "COORD=VALUE", num_args = 1.., value_parser = crate::parse_set)]
    pub at: Vec<(String, f64)>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Draw every mode's shape, animated, to this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub animate: Option<PathBuf>,
    /// Report an unstable equilibrium (Ω² < 0) instead of rejecting it.
    #[arg(long)]
    pub allow_unstable: bool,
    /// Override a parameter: --set k=2 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Most modes drawn by `--animate`.
const MAX_ANIMATED: usize = 12;
/// Most coordinates whose mode shapes are printed in the text output.
const MAX_PRINTED_SHAPE: usize = 8;

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    crate::files::refuse_overwrite(&[&args.model], &[args.animate.as_deref()]).map_err(Failure::usage)?;
    let path = &args.model;
    let (source, d) = crate::derive_file(path, &args.set)?;
    d.reject_constraints("`lagrange modes`").map_err(|e| Failure::model(path, &source, e))?;
    let config = ModesConfig { at: args.at.clone() };
    let modes = mech::normal_modes(&d, &config).map_err(|e| Failure::analysis(path, &source, e))?;
    if !modes.stable && !args.allow_unstable {
        let unstable: Vec<String> = modes
            .modes
            .iter()
            .filter(|m| m.kind == ModeKind::Unstable)
            .map(|m| format!("Ω² = {} along {}", human(m.omega_squared), vector(&modes.coordinates, &m.shape)))
            .collect();
        return Err(Failure::Input {
            file: path.display().to_string(),
            message: format!(
                "the equilibrium at {} is unstable ({}): a small displacement grows like exp(sqrt(-Ω²)·t) instead of oscillating",
                vector(&modes.coordinates, &modes.equilibrium),
                unstable.join("; ")
            ),
            located: None,
            help: Some(
                "start next to a stable equilibrium with --at q=v (e.g. a pendulum's lowest position), or pass --allow-unstable to see the growth rates"
                    .into(),
            ),
        });
    }
    if let Some(svg) = &args.animate {
        std::fs::write(svg, animation(&d, &modes))
            .map_err(|e| Failure::run(format!("cannot write the animation {}: {e}", svg.display())))?;
    }
    let text = match args.format {
        ReportFormat::Json => {
            let report = mech::ModesReport::new(&d, &modes);
            let mut s =
                serde_json::to_string_pretty(&report).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => text(&d, &modes, args.at.is_empty()),
    };
    crate::write_stdout(&text)
}

fn vector(names: &[String], values: &[f64]) -> String {
    let parts: Vec<String> = names.iter().zip(values).map(|(n, v)| format!("{n} = {}", human(*v))).collect();
    format!("({})", parts.join(", "))
}

fn matrix_lines(m: &[Vec<f64>]) -> Vec<String> {
    let cells: Vec<Vec<String>> = m.iter().map(|row| row.iter().map(|v| human(*v)).collect()).collect();
    let width = cells.iter().flatten().map(|c| c.chars().count()).max().unwrap_or(1);
    cells
        .iter()
        .map(|row| format!("[ {} ]", row.iter().map(|c| format!("{c:>width$}")).collect::<Vec<_>>().join("  ")))
        .collect()
}

fn text(d: &Derivation, m: &Modes, from_initial: bool) -> String {
    let n = m.coordinates.len();
    let mut s = String::new();
    let _ = writeln!(s, "{} — small oscillations (notes, Sec. 3.3)\n", d.model().name);
    let _ = writeln!(
        s,
        "Equilibrium (∂U/∂q = 0; damped Newton from {}, {} iteration{}, |∂U/∂q| = {}):",
        if from_initial { "[initial]" } else { "--at" },
        m.newton_iterations,
        if m.newton_iterations == 1 { "" } else { "s" },
        human(m.gradient_norm)
    );
    let width = m.coordinates.iter().map(|c| c.chars().count()).max().unwrap_or(1);
    if n > MAX_PRINTED_SHAPE && m.equilibrium.iter().all(|&v| v == 0.0) {
        let _ = writeln!(s, "  every coordinate = 0");
    } else {
        for (c, v) in m.coordinates.iter().zip(&m.equilibrium).take(MAX_PRINTED_SHAPE) {
            let _ = writeln!(s, "  {c:<width$} = {}", human(*v));
        }
        if n > MAX_PRINTED_SHAPE {
            let _ = writeln!(s, "  … ({} more; see --format json)", n - MAX_PRINTED_SHAPE);
        }
    }
    let _ = writeln!(s, "  U(q₀) = {}\n", human(m.potential));
    let _ = writeln!(s, "L ≈ ½ q'ᵀ T q' − ½ (q − q₀)ᵀ U (q − q₀), with T = M(q₀) and U = ∂²U/∂q∂q at q₀:");
    if n <= MAX_PRINTED_SHAPE {
        let (tl, ul) = (matrix_lines(&m.t_matrix), matrix_lines(&m.u_matrix));
        let tw = tl.iter().map(|l| l.chars().count()).max().unwrap_or(0);
        for i in 0..n {
            let (tlabel, ulabel) = if i == 0 { ("T = ", "U = ") } else { ("    ", "    ") };
            let _ = writeln!(s, "  {tlabel}{:<tw$}    {ulabel}{}", tl[i], ul[i]);
        }
    } else {
        let _ = writeln!(s, "  ({n}×{n} matrices; see --format json)");
    }
    if let Some(sym) = &m.symbolic {
        let pool = &sym.pool;
        let rows = |mm: &[Vec<sym::ExprId>]| -> String {
            let r: Vec<String> = mm
                .iter()
                .map(|row| {
                    format!("[{}]", row.iter().map(|&e| pool.display(e).to_string()).collect::<Vec<_>>().join(", "))
                })
                .collect();
            format!("[{}]", r.join(", "))
        };
        let _ = writeln!(s, "  symbolically: T = {}", rows(&sym.t_matrix));
        let _ = writeln!(s, "                U = {}", rows(&sym.u_matrix));
        let _ = writeln!(s, "\nSecular equation det(U − Ω²T) = 0 (Om is Ω):");
        let _ = writeln!(s, "  {} = 0", pool.display(sym.secular));
    }
    let _ = writeln!(s, "\nNormal frequencies, ascending; mode shapes a with aᵀ T a = 1 (U a = Ω² T a):");
    let exact = m.symbolic.as_ref().and_then(|x| x.frequencies.as_ref().map(|f| (f, &x.pool)));
    for (j, mode) in m.modes.iter().enumerate() {
        let label = format!("Ω{}", j + 1);
        let value = match mode.kind {
            ModeKind::Oscillation => human(mode.frequency.unwrap_or(0.0)),
            ModeKind::Free => "0   (free motion: U is constant along this mode)".into(),
            ModeKind::Unstable => {
                format!(
                    "imaginary: Ω² = {}, growth rate {}",
                    human(mode.omega_squared),
                    human((-mode.omega_squared).sqrt())
                )
            }
        };
        let _ = writeln!(s, "  {label} = {value}");
        if let Some((ex, pool)) = exact {
            let _ = writeln!(s, "       = {}", pool.display(ex[j]));
        }
        if n <= MAX_PRINTED_SHAPE {
            let _ = writeln!(s, "       a = {}", vector(&m.coordinates, &mode.shape));
        }
    }
    if n > MAX_PRINTED_SHAPE {
        let _ = writeln!(s, "  (mode shapes of {n} coordinates: see --format json or --animate)");
    }
    let _ = writeln!(s);
    if m.stable {
        let _ = writeln!(
            s,
            "Stable: every Ω² ≥ 0, so U has a minimum at q₀ (up to free motions) and a small displacement q − q₀ = Σ a_λ A_λ cos(Ω_λ t + δ_λ) stays small."
        );
    } else {
        let _ = writeln!(
            s,
            "Unstable: some Ω² < 0, so U is not a minimum at q₀; a displacement along such a mode grows exponentially."
        );
    }
    for note in &m.notes {
        let _ = writeln!(s, "Note: {note}.");
    }
    s
}

/// An SVG with one row per mode: the coordinates side by side, each displaced
/// by its amplitude in the mode, oscillating with the mode's frequency (SMIL
/// animation; a static envelope shows the shape when the file is printed).
fn animation(d: &Derivation, m: &Modes) -> String {
    let n = m.coordinates.len();
    let shown = m.modes.len().min(MAX_ANIMATED);
    let (width, row_h, top) = (900.0, 120.0, 60.0);
    let height = top + row_h * shown as f64 + 30.0;
    let left = 190.0;
    let span = width - left - 40.0;
    let x_of = |i: usize| left + if n == 1 { span / 2.0 } else { span * i as f64 / (n - 1) as f64 };
    let min_omega = m.modes.iter().filter_map(|x| x.frequency).filter(|&w| w > 0.0).fold(f64::INFINITY, f64::min);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="20" y="30" font-size="20" font-weight="bold">{} — normal modes</text>"#,
        escape(&d.model().name)
    );
    let _ = writeln!(
        s,
        r##"<text x="20" y="50" font-size="13" fill="#666">each dot is one coordinate, displaced by its amplitude in the mode (aᵀTa = 1); animation periods ∝ 1/Ω{}</text>"##,
        if m.modes.len() > shown { format!("; the lowest {shown} of {} modes", m.modes.len()) } else { String::new() }
    );
    for (j, mode) in m.modes.iter().take(shown).enumerate() {
        let y0 = top + row_h * (j as f64 + 0.5);
        let big = mode.shape.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        let amp = 0.4 * row_h / big;
        let label = match mode.kind {
            ModeKind::Oscillation => format!("Ω{} = {}", j + 1, human(mode.frequency.unwrap_or(0.0))),
            ModeKind::Free => format!("Ω{} = 0 (free)", j + 1),
            ModeKind::Unstable => format!("Ω{}² = {} (unstable)", j + 1, human(mode.omega_squared)),
        };
        let _ = writeln!(s, r##"<text x="20" y="{:.1}" font-size="15">{}</text>"##, y0 + 5.0, escape(&label));
        let _ = writeln!(s, r##"<line x1="{left}" y1="{y0:.1}" x2="{:.1}" y2="{y0:.1}" stroke="#ccc"/>"##, left + span);
        let points = |phase: f64| -> String {
            (0..n)
                .map(|i| format!("{:.1},{:.1}", x_of(i), y0 - amp * mode.shape[i] * phase))
                .collect::<Vec<_>>()
                .join(" ")
        };
        // The envelope (static shape).
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#f28e2b" stroke-dasharray="4 3"/>"##,
            points(1.0)
        );
        let dur = match mode.frequency {
            Some(w) if w > 0.0 && min_omega.is_finite() => (3.0 * min_omega / w).max(0.3),
            _ => 3.0,
        };
        let phases: Vec<f64> = (0..=24).map(|k| (2.0 * std::f64::consts::PI * k as f64 / 24.0).cos()).collect();
        let animated = mode.kind != ModeKind::Unstable;
        let values: Vec<String> = phases.iter().map(|&p| points(p)).collect();
        let _ = write!(s, r##"<polyline points="{}" fill="none" stroke="#4e79a7" stroke-width="2">"##, points(1.0));
        if animated {
            let _ = write!(
                s,
                r#"<animate attributeName="points" dur="{dur:.3}s" repeatCount="indefinite" values="{}"/>"#,
                values.join(";")
            );
        }
        let _ = writeln!(s, "</polyline>");
        for i in 0..n {
            let ys: Vec<String> = phases.iter().map(|&p| format!("{:.1}", y0 - amp * mode.shape[i] * p)).collect();
            let _ = write!(
                s,
                r##"<circle cx="{:.1}" cy="{:.1}" r="{}" fill="#4e79a7">"##,
                x_of(i),
                y0 - amp * mode.shape[i],
                if n > 20 { 2.5 } else { 5.0 }
            );
            if animated {
                let _ = write!(
                    s,
                    r#"<animate attributeName="cy" dur="{dur:.3}s" repeatCount="indefinite" values="{}"/>"#,
                    ys.join(";")
                );
            }
            let _ = writeln!(s, "</circle>");
            if n <= MAX_PRINTED_SHAPE && j + 1 == shown {
                let _ = writeln!(
                    s,
                    r##"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle" fill="#666">{}</text>"##,
                    x_of(i),
                    y0 + row_h / 2.0 + 5.0,
                    escape(&m.coordinates[i])
                );
            }
        }
    }
    s.push_str("</svg>\n");
    s
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}
