//! The figures the README quotes (its results table, `docs/results.md.in`) come from here: a test
//! that measures one calls [`record`], which writes it to `target/measurements/KEY.json` and
//! holds it to the value in `docs/measurements.json` (the last full run's, gathered by
//! `scripts/measurements.py`), so a change that moves a quoted figure fails until the figures
//! are measured again and the README regenerated. `tests/readme.rs` checks that every figure
//! the README quotes is in that file and printed from it.

use std::path::PathBuf;

/// Where the suite writes its figures: `$CARGO_TARGET_DIR/measurements` or `target/measurements`.
pub fn measurements_dir() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map(|t| if t.is_absolute() { t } else { root.join(t) })
        .unwrap_or_else(|| root.join("target"))
        .join("measurements")
}

/// Records figure `key` = `value` and checks it against `docs/measurements.json`: within
/// `tolerance` of it relative to its magnitude (a deterministic figure moves only when the code
/// does; a figure at rounding level, such as GPU against CPU in float32, gets a looser one for
/// other devices' arithmetic). With `ANTIRADIANCE_RECORD_FIGURES=1` the check is skipped (a
/// run that measures the figures anew); with `ANTIRADIANCE_TEST_F16_ACCUMULATION=1` nothing is
/// recorded (those runs measure another configuration).
pub fn record(key: &str, value: f64, tolerance: f64) {
    if super::force_f16_accumulation() {
        return;
    }
    assert!(value.is_finite(), "figure {key} is {value}");
    let dir = measurements_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let test = std::env::args()
        .next()
        .and_then(|a| {
            std::path::Path::new(&a)
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
        })
        .unwrap_or_default();
    // The binary's name less cargo's hash suffix.
    let test = test
        .rsplit_once('-')
        .map_or(test.clone(), |(n, _)| n.to_string());
    let line = serde_json::json!({ "key": key, "value": value, "test": test });
    std::fs::write(dir.join(format!("{key}.json")), line.to_string()).unwrap();
    if std::env::var_os("ANTIRADIANCE_RECORD_FIGURES").is_some() {
        return;
    }
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/measurements.json");
    let known: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let Some(want) = known["figures"][key]["value"].as_f64() else {
        panic!(
            "figure {key} = {value} is not in docs/measurements.json: measure the figures \
             (ANTIRADIANCE_RECORD_FIGURES=1 cargo test --release) and run scripts/measurements.py"
        );
    };
    assert!(
        (value - want).abs() <= tolerance * want.abs().max(value.abs()),
        "figure {key}: measured {value}, docs/measurements.json (and the README) say {want}; \
         measure the figures again (ANTIRADIANCE_RECORD_FIGURES=1 cargo test --release) and run \
         scripts/measurements.py"
    );
}
