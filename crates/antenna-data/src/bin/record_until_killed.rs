//! Test helper (not part of the daemon): records the synthetic trial of
//! `antenna_data::record` to the MCAP file given as the only argument, forever, at about
//! 1 kHz of wall time with the recorder's own 100 ms flushes (with the synthetic rig, so
//! with the Foxglove channels, and an estimate every 10 polls), and prints `flushed N` (N
//! segment polls that are durable) after every flush. `tests/record_kill.rs` kills it with
//! SIGKILL and reads the file back.

use std::io::Write as _;
use std::time::Duration;

use antenna_data::record::{
    TrialRecorder, synthetic_estimate, synthetic_metadata, synthetic_rig, synthetic_segments,
    synthetic_servo, synthetic_stage,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args_os()
        .nth(1)
        .ok_or("usage: record-until-killed FILE.mcap")?;
    let mut metadata = synthetic_metadata("killed");
    metadata.rig = Some(synthetic_rig(9));
    let mut recorder = TrialRecorder::create(&path, &metadata)?;
    let stdout = std::io::stdout();
    let mut last_flushed = 0;
    for i in 0u64.. {
        recorder.record_segments(&synthetic_segments(i, 9))?;
        if i % 10 == 0 {
            recorder.record_stage(&synthetic_stage(i / 10))?;
            recorder.record_estimate(&synthetic_estimate(i / 10))?;
        }
        if i % 20 == 0 {
            recorder.record_servo(&synthetic_servo(i / 20))?;
        }
        let flushed = recorder.flushed().segments;
        if flushed != last_flushed {
            last_flushed = flushed;
            let mut out = stdout.lock();
            writeln!(out, "flushed {flushed}")?;
            out.flush()?;
        }
        if i % 4 == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    Ok(())
}
