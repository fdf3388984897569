//! `antennad`: the antenna host daemon. With no hardware configured it runs the simulated
//! rig: nine segments running the firmware's own logic on a virtual I2C bus, polled on
//! absolute deadlines, decoded and shown as they arrive.

use antenna_protocol::{Calibration, Direction};
use anyhow::{Result, bail};
use clap::Parser;
use host_daemon::{Poller, ScriptedSweep, SimBus, SimSegment};
use std::time::{Duration, Instant};

/// The antenna host daemon (simulated rig).
#[derive(Debug, Parser)]
#[command(version, about)]
struct Args {
    /// Segments on the antenna (flexible joints).
    #[arg(long, default_value_t = 9)]
    segments: usize,
    /// Poll rate, hertz.
    #[arg(long, default_value_t = 200.0)]
    poll_hz: f64,
    /// Trial duration, seconds (0 runs until interrupted).
    #[arg(long, default_value_t = 20.0)]
    duration_s: f64,
    /// Lines printed per second.
    #[arg(long, default_value_t = 4.0)]
    print_hz: f64,
    /// First segment address; segment k answers at first + k.
    #[arg(long, default_value_t = 0x20, value_parser = parse_address)]
    first_address: u8,
}

fn parse_address(text: &str) -> Result<u8, String> {
    let value = match text.strip_prefix("0x") {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => text.parse(),
    }
    .map_err(|e| format!("not an address: {e}"))?;
    if antenna_protocol::is_assignable_address(value) {
        Ok(value)
    } else {
        Err(format!(
            "{value:#04x} is outside the assignable range 0x08..=0x77"
        ))
    }
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.segments == 0 || args.segments > 64 {
        bail!("--segments must be 1..=64, got {}", args.segments);
    }
    if !(args.poll_hz.is_finite() && args.poll_hz > 0.0 && args.poll_hz <= 10_000.0) {
        bail!("--poll-hz must be in (0, 10000], got {}", args.poll_hz);
    }
    let last = usize::from(args.first_address) + args.segments - 1;
    let last = u8::try_from(last)
        .ok()
        .filter(|&a| antenna_protocol::is_assignable_address(a));
    let Some(_) = last else {
        bail!(
            "{} segments from address {:#04x} run past 0x77",
            args.segments,
            args.first_address
        );
    };

    // Each magnet is press-fit at its own angle: give every simulated segment its own zero.
    let addresses: Vec<u8> = (0..args.segments)
        .map(|k| args.first_address + k as u8)
        .collect();
    let calibrations: Vec<Calibration> = (0..args.segments)
        .map(|k| {
            let direction = if k % 2 == 0 {
                Direction::CounterClockwise
            } else {
                Direction::Clockwise
            };
            Calibration::new(1500 + 97 * k as u16, direction)
        })
        .collect();
    let segments = addresses
        .iter()
        .zip(&calibrations)
        .map(|(&address, &calibration)| SimSegment::new(address, calibration))
        .collect();
    let mut poller = Poller::new(SimBus::new(segments), &addresses);
    let sweep = ScriptedSweep {
        joints: args.segments,
        ..ScriptedSweep::default()
    };

    println!(
        "antennad: simulated rig, {} segments at {:#04x}..={:#04x}, polling at {} Hz{}",
        args.segments,
        addresses[0],
        addresses[addresses.len() - 1],
        args.poll_hz,
        if args.duration_s > 0.0 {
            format!(" for {} s", args.duration_s)
        } else {
            " until interrupted".to_owned()
        }
    );
    println!("  (scripted wall sweep: the stage runs out and back, the tip bends and touches)");
    println!(
        "{:>7} {:>8}  joint angles, deg (base to tip)   touch",
        "t_s", "stage_mm"
    );

    let period = Duration::from_secs_f64(1.0 / args.poll_hz);
    let print_every = ((args.poll_hz / args.print_hz.max(0.01)).round() as u64).max(1);
    let start = Instant::now();
    let mut late_us: Vec<f64> = Vec::new();
    let mut tick: u64 = 0;
    loop {
        // Absolute deadlines: tick k is due at start + k * period, so no drift accumulates.
        let deadline = start + period.mul_f64(tick as f64);
        let now = Instant::now();
        if deadline > now {
            std::thread::sleep(deadline - now);
        }
        late_us.push(
            Instant::now()
                .saturating_duration_since(deadline)
                .as_secs_f64()
                * 1e6,
        );
        let t_s = tick as f64 * period.as_secs_f64();
        if args.duration_s > 0.0 && t_s > args.duration_s {
            break;
        }

        let rig = sweep.at(t_s);
        let bus = poller.bus_mut();
        for (k, (&angle, &touch)) in rig.joint_angles_rad.iter().zip(&rig.touch).enumerate() {
            if let Some(segment) = bus.segment_mut(k) {
                segment.set_angle_rad(angle);
                segment.set_touch(touch);
            }
        }
        bus.sample_all();
        let readings = poller.poll_all();

        if tick.is_multiple_of(print_every) {
            let mut angles = String::new();
            let mut touches = String::new();
            for (reading, calibration) in readings.iter().zip(&calibrations) {
                match reading.result {
                    Ok(word) => {
                        let deg = calibration.angle_rad(word.angle_counts()).to_degrees();
                        angles.push_str(&format!("{deg:6.1}"));
                        touches.push(if word.touch().any() { '#' } else { '.' });
                    }
                    Err(_) => {
                        angles.push_str("   ---");
                        touches.push('?');
                    }
                }
            }
            println!("{t_s:7.2} {:8.1} {angles}   {touches}", rig.stage_m * 1e3);
        }
        tick += 1;
    }

    late_us.sort_by(f64::total_cmp);
    let percentile = |p: f64| late_us[((late_us.len() - 1) as f64 * p) as usize];
    println!(
        "antennad: {} polls; wake-up lateness p50 {:.0} us, p99 {:.0} us",
        tick,
        percentile(0.5),
        percentile(0.99)
    );
    for (address, health) in addresses.iter().zip(poller.health()) {
        if !health.all_ok() {
            println!("  segment {address:#04x}: {health:?}");
        }
    }
    let failures: u64 = poller
        .health()
        .iter()
        .map(|h| h.nacks + h.pec_errors + h.bus_errors)
        .sum();
    println!(
        "antennad: {} samples, {} failed polls",
        poller.health().iter().map(|h| h.ok).sum::<u64>(),
        failures
    );
    Ok(())
}
