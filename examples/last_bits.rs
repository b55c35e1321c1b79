//! The continuation claims of the history match under a last-bit change of the arithmetic:
//! evaluates each of the 40 points of `tests/fixtures/history_points.csv` (the first 20 runs
//! of the first wave of each prototype of the recorded match) as recorded and with the drive
//! amplitude scaled by (1 + k eps), eps the machine epsilon, and prints each point's failed
//! quantities both ways and every quantity whose outcome changes (a failure, a value that
//! becomes absent, or a value that moves by more than `REL_CHANGE`).
//!
//! A change of the drive by a few ulps moves every orbit by rounding-level amounts, as a
//! differently rounded `sin` or a reordered product does: a continuation that keeps its branch
//! gives the same outcomes both ways, and the same values to its location tolerance.
//!
//! Usage: `cargo run --release --example last_bits -- [k] [p1:2 p2:6 ...]` (k 4 by default;
//! points as `prototype:run`, none: all 40).

use endstop::device::Device;
use endstop::paper::claims::Claims;
use endstop::paper::deviations::{evaluate, Evaluation, Outcome, Prototype, RangesFile, Scope};

/// The relative change of a value that counts as a change of branch or event: a thousand
/// times the events' location tolerance relative to their parameter (1e-4 Hz at ~1 kHz, 1e-6 g
/// at ~1 g), far above rounding and far below the distance between two branches' events.
const REL_CHANGE: f64 = 1e-3;

const POINTS: &str = include_str!("../tests/fixtures/history_points.csv");

/// One recorded point: its prototype, run number, unit-cube coordinates and the quantities
/// whose continuation failed in the record.
struct Point {
    prototype: Prototype,
    label: String,
    coords: Vec<f64>,
    recorded_failed: String,
}

fn points() -> Result<Vec<Point>, Box<dyn std::error::Error>> {
    let mut out = Vec::new();
    for line in POINTS.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let prototype = match f[0] {
            "p1" => Prototype::P1,
            "p2" => Prototype::P2,
            other => return Err(format!("unknown prototype {other}").into()),
        };
        let coords = f[2..10]
            .iter()
            .map(|s| s.parse::<f64>())
            .collect::<Result<Vec<_>, _>>()?;
        out.push(Point {
            prototype,
            label: format!("{}:{}", f[0], f[1]),
            coords,
            recorded_failed: f.get(10).unwrap_or(&"").to_string(),
        });
    }
    Ok(out)
}

fn describe(o: Outcome) -> String {
    match o {
        Outcome::Value(v) => format!("{v:.6}"),
        other => format!("{other:?}"),
    }
}

/// Whether two evaluations of one quantity differ by more than rounding.
fn changed(a: &Evaluation, b: &Evaluation) -> bool {
    match (a.outcome, b.outcome) {
        (Outcome::Value(x), Outcome::Value(y)) => {
            (x - y).abs() > REL_CHANGE * x.abs().max(y.abs()).max(1e-300)
        }
        (x, y) => x != y,
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).peekable();
    let k: f64 = match args.peek().map(|a| a.parse::<f64>()) {
        Some(Ok(k)) => {
            args.next();
            k
        }
        _ => 4.0,
    };
    let chosen: Vec<String> = args.collect();
    let root = env!("CARGO_MANIFEST_DIR");
    let p1 = Device::from_toml_str(
        &std::fs::read_to_string(format!("{root}/data/prototype1.toml"))?,
        "prototype1",
    )?;
    let p2 = Device::from_toml_str(
        &std::fs::read_to_string(format!("{root}/data/prototype2.toml"))?,
        "prototype2",
    )?;
    let claims = Claims::bundled()?;
    let ranges = RangesFile::bundled()?;
    let scale = 1.0 + k * f64::EPSILON;
    println!("drive amplitude scaled by 1 + {k} eps; values compared to {REL_CHANGE:e} relative");
    let (mut failed_base, mut failed_pert, mut moved_points) = (0, 0, 0);
    for p in points()? {
        if !chosen.is_empty() && !chosen.contains(&p.label) {
            continue;
        }
        let (base, r) = match p.prototype {
            Prototype::P1 => (&p1, &ranges.prototype1),
            Prototype::P2 => (&p2, &ranges.prototype2),
        };
        let variant = r.variant(base, &p.coords)?;
        let mut perturbed = variant.clone();
        perturbed.accel_scale *= scale;
        let t0 = std::time::Instant::now();
        let a = evaluate(p.prototype, &variant, &claims, Scope::default())?;
        let b = evaluate(p.prototype, &perturbed, &claims, Scope::default())?;
        let failed = |e: &[Evaluation]| {
            e.iter()
                .filter(|x| x.outcome == Outcome::Failed)
                .map(|x| x.quantity.quantity)
                .collect::<Vec<_>>()
        };
        let (fa, fb) = (failed(&a), failed(&b));
        failed_base += usize::from(!fa.is_empty());
        failed_pert += usize::from(!fb.is_empty());
        let moved: Vec<String> = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| changed(x, y))
            .map(|(x, y)| {
                format!(
                    "{} {} -> {}",
                    x.quantity.quantity,
                    describe(x.outcome),
                    describe(y.outcome)
                )
            })
            .collect();
        moved_points += usize::from(!moved.is_empty());
        println!(
            "{:6} {:5.1} s  failed: [{}] perturbed: [{}] recorded: [{}]",
            p.label,
            t0.elapsed().as_secs_f64(),
            fa.join(" "),
            fb.join(" "),
            p.recorded_failed.replace(';', " ")
        );
        for m in moved {
            println!("         changed: {m}");
        }
    }
    println!(
        "points with a failure: {failed_base} as given, {failed_pert} perturbed; \
         points whose outcomes change: {moved_points}"
    );
    Ok(())
}
