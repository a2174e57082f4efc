//! `profile --trace`: the profiled run as a Chrome trace-event file (JSON, opened by Perfetto and
//! `chrome://tracing`). Two tracks: the device (every pass of every timed iteration, its
//! duration from the pass's GPU timestamps) and the host (the setup phases, each batch's
//! submission-and-wait). The device has no clock shared with the host here, so each batch's
//! passes are laid end to end from the moment the host submitted it: durations are measured,
//! start times within a batch are the sum of the durations before (the gaps between passes are
//! not recorded).

use serde::Serialize;
use serde_json::{json, Value};

/// One timed batch: when the host submitted it, how long until its fence, and its passes.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Batch {
    /// Host time of the submission, ms since the profile began.
    pub start_ms: f64,
    /// Submission to completion, wall time (ms).
    pub wall_ms: f64,
    /// Iterations in the batch.
    pub iterations: usize,
    /// Per-iteration pass durations (ms), in recording order, the same for each iteration
    /// of the batch (the batch's timestamps averaged over its iterations).
    pub passes: Vec<(String, f64)>,
}

/// A host phase before the timed batches (linking, uploads, ...), laid end to end from 0.
#[derive(Debug, Clone, Serialize)]
pub struct Phase {
    /// Name.
    pub name: String,
    /// Duration (ms).
    pub ms: f64,
}

const PID: u32 = 1;
const DEVICE: u32 = 1;
const HOST: u32 = 2;

fn event(name: &str, tid: u32, start_ms: f64, ms: f64, args: Value) -> Value {
    json!({"name": name, "cat": if tid == DEVICE { "device" } else { "host" }, "ph": "X",
           "pid": PID, "tid": tid, "ts": start_ms * 1e3, "dur": ms * 1e3, "args": args})
}

/// The trace-event document of a profile: `device` names the device track.
pub fn chrome_trace(device: &str, setup: &[Phase], batches: &[Batch]) -> Value {
    let mut events = vec![
        json!({"name": "process_name", "ph": "M", "pid": PID, "args": {"name": "antiradiance profile"}}),
        json!({"name": "thread_name", "ph": "M", "pid": PID, "tid": DEVICE, "args": {"name": format!("device: {device}")}}),
        json!({"name": "thread_name", "ph": "M", "pid": PID, "tid": HOST, "args": {"name": "host"}}),
    ];
    let mut t = 0.0;
    for p in setup {
        events.push(event(&p.name, HOST, t, p.ms, json!({})));
        t += p.ms;
    }
    for (b, batch) in batches.iter().enumerate() {
        events.push(event(
            "submit and wait",
            HOST,
            batch.start_ms,
            batch.wall_ms * batch.iterations as f64,
            json!({"batch": b, "iterations": batch.iterations}),
        ));
        let mut at = batch.start_ms;
        for i in 0..batch.iterations {
            for (name, ms) in &batch.passes {
                events.push(event(
                    name,
                    DEVICE,
                    at,
                    *ms,
                    json!({"batch": b, "iteration": i}),
                ));
                at += ms;
            }
        }
    }
    json!({"traceEvents": events, "displayTimeUnit": "ms",
           "otherData": {"note": "device passes: GPU-timestamp durations laid end to end from each batch's submission"}})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_become_complete_events_on_the_device_track() {
        let b = Batch {
            start_ms: 10.0,
            wall_ms: 3.0,
            iterations: 2,
            passes: vec![("global".into(), 1.0), ("local".into(), 0.5)],
        };
        let t = chrome_trace(
            "llvmpipe",
            &[Phase {
                name: "linking".into(),
                ms: 4.0,
            }],
            &[b],
        );
        let ev = t["traceEvents"].as_array().unwrap();
        let device: Vec<&Value> = ev
            .iter()
            .filter(|e| e["tid"] == DEVICE && e["ph"] == "X")
            .collect();
        assert_eq!(device.len(), 4);
        assert_eq!(device[1]["name"], "local");
        assert_eq!(device[1]["ts"], 11000.0);
        assert_eq!(device[3]["ts"], 12500.0);
        assert_eq!(device[3]["dur"], 500.0);
    }
}
