//! `profile --trace` (issue 33 item 5): the file is a Chrome trace-event document with a device
//! track holding every timed pass and a host track, and its pass durations are the table's.

mod common;

use serde_json::Value;

#[test]
fn trace_parses_and_its_passes_are_the_tables() {
    let d = common::Scratch::new("trace");
    let (trace, json) = (d.join("trace.json"), d.join("profile.json"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_antiradiance"))
        .args([
            "profile", "--bins", "32", "--frames", "4", "--warmup", "1", "--trace",
        ])
        .arg(&trace)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t: Value = serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let p: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let events = t["traceEvents"].as_array().unwrap();
    let complete: Vec<&Value> = events.iter().filter(|e| e["ph"] == "X").collect();
    for e in &complete {
        assert!(
            e["ts"].as_f64().unwrap() >= 0.0 && e["dur"].as_f64().unwrap() >= 0.0,
            "{e}"
        );
    }
    let named = |tid: u64| {
        events
            .iter()
            .find(|e| e["ph"] == "M" && e["name"] == "thread_name" && e["tid"] == tid)
            .map(|e| e["args"]["name"].as_str().unwrap().to_string())
    };
    assert!(named(1).unwrap().starts_with("device"), "{:?}", named(1));
    assert_eq!(named(2).as_deref(), Some("host"));
    let host: Vec<&str> = complete
        .iter()
        .filter(|e| e["tid"] == 2)
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert!(
        host.contains(&"linking") && host.contains(&"submit and wait"),
        "{host:?}"
    );
    let passes = p["passes"].as_object().unwrap();
    assert!(passes.contains_key("global") && passes.contains_key("local"));
    for (name, stats) in passes {
        let mut d: Vec<f64> = complete
            .iter()
            .filter(|e| e["tid"] == 1 && e["name"] == name.as_str())
            .map(|e| e["dur"].as_f64().unwrap() / 1e3)
            .collect();
        // Every timed iteration has each pass once.
        assert_eq!(d.len(), 4, "{name}");
        d.sort_by(f64::total_cmp);
        let median = (d[1] + d[2]) / 2.0;
        let want = stats["median_ms"].as_f64().unwrap();
        assert!(
            (median - want).abs() <= 1e-9 * want.max(1.0),
            "{name}: {median} vs {want}"
        );
    }
}
