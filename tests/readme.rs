//! The README's results table is `docs/results.md.in` printed from `docs/measurements.json`
//! (the figures the test suite measured, gathered by `scripts/measurements.py`): every figure it
//! quotes must be in that file, and the table must be what the template prints now. Each test
//! that measures a figure holds it to the file (`common::record`), so a figure cannot go stale.

use std::path::Path;

const BEGIN: &str = "<!-- results: printed by scripts/measurements.py from docs/results.md.in -->";
const END: &str = "<!-- end of results -->";

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel))
        .unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// scripts/measurements.py `fmt`: fixed (f), percent (p, signed sp), integer (i), ratio (x),
/// scientific as a·10ⁿ (e); the digit count after the letters.
fn fmt(value: f64, spec: &str) -> String {
    let split = spec
        .find(|c: char| c.is_ascii_digit())
        .unwrap_or(spec.len());
    let (kind, digits) = spec.split_at(split);
    let n: usize = digits.parse().unwrap_or(0);
    let minus = if value < 0.0 { "−" } else { "" };
    match kind {
        "f" => format!("{value:.n$}"),
        "p" => format!("{:.n$}%", value.abs() * 100.0),
        "sp" => format!(
            "{}{:.n$}%",
            if value >= 0.0 { "+" } else { "−" },
            value.abs() * 100.0
        ),
        "i" => {
            let digits = format!("{}", value.round().abs() as u64);
            let mut out = String::new();
            for (k, c) in digits.chars().enumerate() {
                if k > 0 && (digits.len() - k) % 3 == 0 {
                    out.push(',');
                }
                out.push(c);
            }
            format!("{minus}{out}")
        }
        "x" => format!("{value:.n$}×"),
        "e" => {
            let s = format!("{:.n$e}", value.abs());
            let (m, e) = s.split_once('e').unwrap();
            let sup: String = e
                .parse::<i32>()
                .unwrap()
                .to_string()
                .chars()
                .map(|c| match c {
                    '-' => '⁻',
                    d => "⁰¹²³⁴⁵⁶⁷⁸⁹"
                        .chars()
                        .nth(d.to_digit(10).unwrap() as usize)
                        .unwrap(),
                })
                .collect();
            format!("{minus}{m}·10{sup}")
        }
        _ => panic!("docs/results.md.in: unknown format {spec}"),
    }
}

/// The template with every `{key:spec}` printed from `figures`; the keys it quotes.
fn render(template: &str, figures: &serde_json::Value) -> (String, Vec<String>) {
    let (mut out, mut keys, mut rest) = (String::new(), Vec::new(), template);
    while let Some(a) = rest.find('{') {
        out.push_str(&rest[..a]);
        let b = a + rest[a..]
            .find('}')
            .expect("an unclosed { in docs/results.md.in");
        let (key, spec) = rest[a + 1..b].split_once(':').expect("{key:spec}");
        let value = figures[key]["value"].as_f64().unwrap_or_else(|| {
            panic!(
                "the README quotes figure {key}, which docs/measurements.json does not have: \
                 measure the figures (ANTIRADIANCE_RECORD_FIGURES=1 cargo test --release) and \
                 run scripts/measurements.py"
            )
        });
        out.push_str(&fmt(value, spec));
        keys.push(key.to_string());
        rest = &rest[b + 1..];
    }
    out.push_str(rest);
    (out, keys)
}

#[test]
fn the_readme_results_are_the_measured_figures() {
    let file: serde_json::Value = serde_json::from_str(&read("docs/measurements.json")).unwrap();
    let figures = &file["figures"];
    let (table, keys) = render(&read("docs/results.md.in"), figures);
    assert!(keys.len() >= 30, "{} figures quoted", keys.len());
    let readme = read("README.md");
    let a = readme.find(BEGIN).expect("the README's results markers") + BEGIN.len();
    let b = readme.find(END).expect("the README's results end marker");
    assert_eq!(
        readme[a..b].trim(),
        table.trim(),
        "the README's results table is not docs/results.md.in printed from docs/measurements.json: \
         run scripts/measurements.py"
    );
    // Every figure in the file came from a test: its binary is named.
    for (key, v) in figures.as_object().unwrap() {
        let test = v["test"].as_str().unwrap_or("");
        assert!(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("tests/{test}.rs"))
                .exists(),
            "figure {key}: no test binary {test:?}"
        );
    }
    println!(
        "{} figures quoted, {} in the file",
        keys.len(),
        figures.as_object().unwrap().len()
    );
}

#[test]
fn the_figure_formats_print_as_the_script_prints_them() {
    assert_eq!(fmt(0.09349, "f3"), "0.093");
    assert_eq!(fmt(0.0204, "p1"), "2.0%");
    assert_eq!(fmt(-0.0089, "sp2"), "−0.89%");
    assert_eq!(fmt(0.0127, "sp2"), "+1.27%");
    assert_eq!(fmt(8373.0, "i"), "8,373");
    assert_eq!(fmt(1.1734, "x2"), "1.17×");
    assert_eq!(fmt(2.6e-6, "e1"), "2.6·10⁻⁶");
    assert_eq!(fmt(9.2e-16, "e0"), "9·10⁻¹⁶");
    assert_eq!(fmt(0.74, "p0"), "74%");
}
