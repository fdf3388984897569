//! `screenshot_check FILE.png`: exits 0 if the monitor's screenshot shows the chain, 1 if
//! not (a blank window), 2 if the file cannot be read. `scripts/monitor-screenshot` runs it.

use std::process::ExitCode;

use antenna_monitor::screenshot::{MIN_CHAIN_EXTENT_PX, MIN_CHAIN_PIXELS, check_png};

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: screenshot_check FILE.png");
        return ExitCode::from(2);
    };
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("screenshot_check: {path}: {e}");
            return ExitCode::from(2);
        }
    };
    match check_png(&bytes) {
        Ok(report) => {
            println!(
                "screenshot_check: {path}: {}x{} px, {} chain-coloured pixels in the chain \
                 panel (need {MIN_CHAIN_PIXELS}), spanning {:?} (need {MIN_CHAIN_EXTENT_PX} px)",
                report.size_px.0, report.size_px.1, report.chain_pixels, report.chain_box_px
            );
            if report.chain_drawn() {
                println!("screenshot_check: the chain is drawn");
                ExitCode::SUCCESS
            } else {
                eprintln!("screenshot_check: {path}: the chain is not drawn (blank window?)");
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("screenshot_check: {path}: {e}");
            ExitCode::from(2)
        }
    }
}
