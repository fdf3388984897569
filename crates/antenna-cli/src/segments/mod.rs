//! `antenna segments scan | assign | zero | status`: commissioning the segments over the
//! daemon's bus, through `antenna-bus`'s `commission` module, as a library: another program
//! runs the command's actions with [`run`] (its output written to any writer), or reads a
//! configuration's bus with [`Config`] and commissions it with [`antenna_bus::commission`]
//! itself. The bus and its segments are antennad's `[bus]` table ([`antenna_bus::config`],
//! read by [`config`]).
//!
//! ```
//! use antenna_cli::segments::{SegmentsCommand, run};
//! use clap::Parser as _;
//!
//! let command = SegmentsCommand::try_parse_from([
//!     "segments", "status", "0x20", "--bus", "sim", "--sim-segment", "0x20:1500", "--json",
//! ])
//! .unwrap();
//! let mut out = Vec::new();
//! run(&command.args, &mut out).unwrap();
//! let status: serde_json::Value = serde_json::from_slice(&out).unwrap();
//! assert_eq!(status["segments"][0]["address_hex"], "0x20");
//! ```

pub mod config;

use std::io::Write;
use std::path::{Path, PathBuf};
#[cfg(target_os = "linux")]
use std::time::Duration;

use antenna_bus::commission::{
    self, ASSIGN_SETTLE, CommissionError, Found, SegmentStatus, ZeroMeasurement,
};
use antenna_bus::{SegmentFault, SimBus, SimSegment};
use anyhow::{Context as _, anyhow};
use clap::{Args, Parser, Subcommand};
use embedded_hal::i2c::I2c;
use serde_json::{Value, json};

pub use config::Config;

/// Why an action did not succeed, which decides the `antenna` command's exit status.
#[derive(Debug, thiserror::Error)]
pub enum SegmentsFailure {
    /// Exit status 1: the bus failed, a segment did not answer or is unhealthy, a check after
    /// a write failed (what was measured or found is already written out).
    #[error("{}", .0.as_ref().map_or_else(String::new, |e| format!("{e:#}")))]
    NoSuccess(Option<anyhow::Error>),
    /// Exit status 2: bad input (arguments, the configuration, a refused assignment).
    #[error("{0:#}")]
    BadInput(anyhow::Error),
}

impl From<anyhow::Error> for SegmentsFailure {
    fn from(e: anyhow::Error) -> Self {
        SegmentsFailure::BadInput(e)
    }
}

type Failure = SegmentsFailure;

fn bail_input<T>(message: String) -> Result<T, Failure> {
    Err(Failure::BadInput(anyhow!(message)))
}

/// Writes `value` as pretty JSON on a line of its own.
fn print_json<T: serde::Serialize>(out: &mut dyn Write, value: &T) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(value).context("writing JSON")?;
    // An error (a closed pipe: `antenna segments status --json | head`), not a panic.
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .context("writing the JSON to stdout")?;
    Ok(())
}

/// `writeln!` to the action's output; a failed write is an error, not a panic.
macro_rules! say {
    ($out:expr, $($arg:tt)*) => {
        writeln!($out, $($arg)*).context("writing to stdout")?
    };
}

/// `antenna segments` as a command of its own, for parsing its arguments in another program
/// (`SegmentsCommand::try_parse_from(["segments", "status", "--bus", "sim"])`).
#[derive(Debug, Parser)]
#[command(name = "segments")]
pub struct SegmentsCommand {
    /// The action and its arguments.
    #[command(flatten)]
    pub args: SegmentsArgs,
}

/// Commission the segments: find them, give them addresses, measure their zeros, read
/// their status.
///
/// The bus is `--bus` (`sim`, or a Linux I2C device such as /dev/i2c-1), else `bus.device`
/// of `--config` (antennad's configuration); one of them is required. `sim` is the simulated
/// rig: the segments of `--config` (the built-in rig's without it), each at rest at joint
/// angle zero, or those `--sim-segment` lists. A simulated bus lives for one invocation: an
/// assignment on it shows what the segment says at its new address, and is gone after.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna segments scan --config /etc/antennad.toml
  antenna segments assign 0x77 0x24 --bus /dev/i2c-1
  antenna segments zero --config /etc/antennad.toml -o antennad-zeroed.toml
  antenna segments status --bus sim --json
  antenna segments scan --bus sim --sim-segment 0x20:1500 --sim-segment 0x77")]
pub struct SegmentsArgs {
    #[command(subcommand)]
    action: Action,
}

#[derive(Debug, Subcommand)]
enum Action {
    Scan(ScanArgs),
    Assign(AssignArgs),
    Zero(ZeroArgs),
    Status(StatusArgs),
}

/// The bus and the output format, shared by every action.
#[derive(Debug, Args)]
struct BusArgs {
    /// `sim` or a Linux I2C device (/dev/i2c-N); default: `bus.device` of --config.
    #[arg(long, value_name = "BUS")]
    bus: Option<String>,
    /// antennad's configuration (TOML): its bus device and its segments.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// A simulated segment instead of the configured ones (repeat for more; --bus sim only):
    /// ADDR, ADDR:ZERO_COUNTS or ADDR:ZERO_COUNTS:rail. At 0x77 it is unassigned (fresh, no address stored);
    /// ZERO_COUNTS is the count its magnet reads at joint angle zero (default 2048); `rail`
    /// puts its angle sensor on a rail (ADC fault).
    #[arg(long, value_name = "SPEC")]
    sim_segment: Vec<String>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

/// List the segments that answer: address, firmware version, status flags, angle, touch.
///
/// Probes every address of the range (a register write and a 3-byte read, as a segment
/// expects). Flags a segment still at the default address 0x77 as unassigned, and an
/// address where more than one segment answers (their reads fail the PEC) as a conflict;
/// with --config, also the configured segments that did not answer. Exit status: 0 scanned;
/// 1 the bus failed; 2 bad input.
#[derive(Debug, Args)]
struct ScanArgs {
    #[command(flatten)]
    bus: BusArgs,
    /// First address to probe.
    #[arg(long, value_name = "ADDR", value_parser = parse_address, default_value = "0x08")]
    from: u8,
    /// Last address to probe.
    #[arg(long, value_name = "ADDR", value_parser = parse_address, default_value = "0x77")]
    to: u8,
}

/// Move the segment at FROM to address TO (register 0x10 with the address's complement).
///
/// Refused, with nothing written, when TO is outside 0x08..=0x77 or is the default 0x77,
/// when anything already answers at TO, when nothing answers at FROM, or when more than one
/// segment answers at FROM (the write would move them all: connect them one at a time).
/// Checked after: the segment answers at TO with its address set, and not at FROM.
/// Exit status: 0 assigned; 1 the check after failed or the bus failed; 2 refused.
#[derive(Debug, Args)]
struct AssignArgs {
    #[command(flatten)]
    bus: BusArgs,
    /// The segment's address now (0x77 for a fresh one).
    #[arg(value_parser = parse_address)]
    from: u8,
    /// Its new address (0x08..=0x76).
    #[arg(value_parser = parse_address)]
    to: u8,
}

/// Measure each joint's zero_counts with the antenna at rest (straight, touching nothing)
/// and write them into a copy of the configuration.
///
/// Each joint's zero is the circular mean of --samples readings (around the 4096-count
/// wrap); the table shows the spread. A joint whose sensor reports an ADC fault or whose
/// touch switches closed is not measured at rest: nothing is written and the exit status
/// is 1. Exit status: 0 measured (and written); 1 a segment failed or was not at rest; 2 bad
/// input.
#[derive(Debug, Args)]
struct ZeroArgs {
    #[command(flatten)]
    bus: BusArgs,
    /// The segments to measure (default: every segment of --config).
    #[arg(value_parser = parse_address)]
    addresses: Vec<u8>,
    /// Readings averaged per joint (one per sample period).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    samples: u64,
    /// Write --config with the measured zero_counts here (comments and layout kept); never
    /// the --config file itself.
    #[arg(short = 'o', long, value_name = "FILE", requires = "config")]
    output: Option<PathBuf>,
    /// Replace FILE if it exists.
    #[arg(long, requires = "output")]
    force: bool,
}

/// Read each segment's firmware version, status flags, angle counts and touch bits.
///
/// Exit status: 0 every segment answered with no status flag set; 1 a segment did not
/// answer, answered in conflict, or has a flag set (the table is still printed); 2 bad
/// input.
#[derive(Debug, Args)]
struct StatusArgs {
    #[command(flatten)]
    bus: BusArgs,
    /// The segments to read (default: every segment of --config).
    #[arg(value_parser = parse_address)]
    addresses: Vec<u8>,
}

/// A 7-bit address: `0x21` or `33`.
fn parse_address(text: &str) -> Result<u8, String> {
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => text.parse::<u8>(),
    };
    match parsed {
        Ok(address) if address <= 0x7F => Ok(address),
        Ok(address) => Err(format!("{address:#04x} is not a 7-bit address")),
        Err(_) => Err(format!(
            "{text:?} is not an address (0x21 or 33, 0x00..=0x7f)"
        )),
    }
}

/// One `--sim-segment` spec: `ADDR[:ZERO_COUNTS[:rail]]`.
fn sim_segment(spec: &str) -> anyhow::Result<SimSegment> {
    let bad = |why: String| anyhow!("--sim-segment {spec:?}: {why} (ADDR[:ZERO_COUNTS[:rail]])");
    let mut parts = spec.split(':');
    let address = parse_address(parts.next().unwrap_or_default()).map_err(bad)?;
    let zero_counts = match parts.next() {
        None | Some("") => 2048,
        Some(text) => match text.parse::<u16>() {
            Ok(counts) if counts <= 4095 => counts,
            _ => return Err(bad(format!("zero counts {text:?} are not 0..=4095"))),
        },
    };
    let fault = match parts.next() {
        None => SegmentFault::None,
        Some("rail") => SegmentFault::SensorRail,
        Some(other) => return Err(bad(format!("unknown fault {other:?}"))),
    };
    if let Some(extra) = parts.next() {
        return Err(bad(format!("unexpected {extra:?}")));
    }
    let calibration = antenna_protocol::Calibration::new(
        zero_counts,
        antenna_protocol::Direction::CounterClockwise,
    );
    let mut segment = if address == antenna_protocol::DEFAULT_ADDRESS {
        SimSegment::unassigned(calibration)
    } else {
        SimSegment::new(address, calibration)
    };
    segment.set_fault(fault);
    Ok(segment)
}

/// The configuration of --config, if given.
fn load_config(bus: &BusArgs) -> Result<Option<Config>, Failure> {
    match &bus.config {
        None => Ok(None),
        Some(path) => Ok(Some(Config::from_file(path).map_err(Failure::BadInput)?)),
    }
}

/// The bus an action runs on, with its name.
enum Opened {
    Sim(SimBus),
    #[cfg(target_os = "linux")]
    Linux(antenna_bus::linux_i2c::LinuxI2cBus),
}

fn open_bus(bus: &BusArgs, config: Option<&Config>) -> Result<(Opened, String), Failure> {
    let device = match (&bus.bus, config) {
        (Some(device), _) => device.clone(),
        (None, Some(config)) => config.device.clone(),
        (None, None) => {
            return bail_input(
                "no bus: give --bus sim, --bus /dev/i2c-N, or --config with [bus] device"
                    .to_owned(),
            );
        }
    };
    if device == "sim" {
        let mut sim = if bus.sim_segment.is_empty() {
            let built_in;
            let config = match config {
                Some(config) => config,
                None => {
                    built_in = Config::built_in();
                    &built_in
                }
            };
            SimBus::new(
                config
                    .segments
                    .iter()
                    .map(|s| SimSegment::new(s.address, s.calibration()))
                    .collect(),
            )
        } else {
            SimBus::new(
                bus.sim_segment
                    .iter()
                    .map(|spec| sim_segment(spec))
                    .collect::<anyhow::Result<_>>()?,
            )
        };
        // The firmware's main loop has run a few sample periods (touch debounced).
        for _ in 0..3 {
            sim.sample_all();
        }
        return Ok((Opened::Sim(sim), device));
    }
    if !bus.sim_segment.is_empty() {
        return bail_input(format!(
            "--sim-segment needs the simulated bus, but the bus is {device}"
        ));
    }
    open_hardware(&device, config)
}

#[cfg(target_os = "linux")]
fn open_hardware(device: &str, config: Option<&Config>) -> Result<(Opened, String), Failure> {
    if !device.starts_with("/dev/") {
        return bail_input(format!(
            "--bus {device:?}: must be `sim` or a device such as /dev/i2c-1"
        ));
    }
    let addresses = config.map(|c| c.addresses()).unwrap_or_default();
    let bus = antenna_bus::linux_i2c::LinuxI2cBus::open(device, &addresses)
        .map_err(anyhow::Error::new)?;
    Ok((Opened::Linux(bus), device.to_owned()))
}

#[cfg(not(target_os = "linux"))]
fn open_hardware(device: &str, _config: Option<&Config>) -> Result<(Opened, String), Failure> {
    bail_input(format!(
        "--bus {device:?}: hardware I2C buses are Linux only; --bus sim runs the simulated rig"
    ))
}

/// Runs the action of `args`, writing its table or JSON (what `antenna segments` prints) to
/// `out`.
///
/// # Errors
/// [`SegmentsFailure`]: bad input, or an action that did not succeed.
pub fn run(args: &SegmentsArgs, out: &mut dyn Write) -> Result<(), Failure> {
    let bus_args = match &args.action {
        Action::Scan(a) => &a.bus,
        Action::Assign(a) => &a.bus,
        Action::Zero(a) => &a.bus,
        Action::Status(a) => &a.bus,
    };
    let config = load_config(bus_args)?;
    let (opened, name) = open_bus(bus_args, config.as_ref())?;
    let context = Ctx {
        name,
        config: config.as_ref(),
        json: bus_args.json,
    };
    match opened {
        Opened::Sim(mut bus) => act(
            &args.action,
            &context,
            &mut bus,
            &mut SimBus::sample_all,
            out,
        ),
        #[cfg(target_os = "linux")]
        Opened::Linux(mut bus) => {
            // The segments sample at 1 kHz: two periods apart, every reading is a new one.
            let mut wait = |_: &mut antenna_bus::linux_i2c::LinuxI2cBus| {
                std::thread::sleep(Duration::from_millis(2));
            };
            act(&args.action, &context, &mut bus, &mut wait, out)
        }
    }
}

/// What every action knows besides its bus.
struct Ctx<'a> {
    name: String,
    config: Option<&'a Config>,
    json: bool,
}

impl Ctx<'_> {
    /// The given addresses, or the configured ones.
    fn addresses(&self, given: &[u8]) -> Result<Vec<u8>, Failure> {
        if !given.is_empty() {
            return Ok(given.to_vec());
        }
        match self.config {
            Some(config) => Ok(config.addresses()),
            None => bail_input(
                "no segments: name their addresses or give --config with [[bus.segments]]"
                    .to_owned(),
            ),
        }
    }

    fn configured(&self, address: u8) -> bool {
        self.config
            .is_some_and(|c| c.segments.iter().any(|s| s.address == address))
    }
}

fn act<I: I2c>(
    action: &Action,
    ctx: &Ctx<'_>,
    bus: &mut I,
    between: &mut dyn FnMut(&mut I),
    out: &mut dyn Write,
) -> Result<(), Failure> {
    match action {
        Action::Scan(args) => scan(args, ctx, bus, out),
        Action::Assign(args) => assign(args, ctx, bus, out),
        Action::Zero(args) => zero(args, ctx, bus, between, out),
        Action::Status(args) => status(args, ctx, bus, out),
    }
}

fn hex(address: u8) -> String {
    format!("{address:#04x}")
}

/// The decoded status flags, as words.
fn flag_names(segment: &SegmentStatus) -> String {
    let flags = segment.flags;
    let mut names = Vec::new();
    if flags.adc_fault() {
        names.push("adc-fault".to_owned());
    }
    if flags.touch_stuck() {
        names.push("touch-stuck".to_owned());
    }
    if flags.address_not_set() {
        names.push("address-not-set".to_owned());
    }
    let unknown = flags.bits() & !antenna_protocol::StatusFlags::DEFINED;
    if unknown != 0 {
        names.push(format!("unknown-bits-{unknown:#04x}"));
    }
    if names.is_empty() {
        "ok".to_owned()
    } else {
        names.join(",")
    }
}

fn found_json(found: &Found, ctx: &Ctx<'_>) -> Value {
    let mut value = json!({
        "address": found.address,
        "address_hex": hex(found.address),
        "configured": ctx.configured(found.address),
    });
    match &found.answer {
        Ok(s) => {
            value["firmware"] = json!(format!("{}.{}", s.version.0, s.version.1));
            value["firmware_matches"] = json!(s.version_matches());
            value["status_bits"] = json!(s.flags.bits());
            value["adc_fault"] = json!(s.flags.adc_fault());
            value["touch_stuck"] = json!(s.flags.touch_stuck());
            value["address_not_set"] = json!(s.flags.address_not_set());
            value["unassigned"] = json!(s.unassigned());
            value["angle_counts"] = json!(s.word.angle_counts());
            value["touch_bits"] = json!(s.word.touch().bits());
            value["counter"] = json!(s.counter);
            value["conflict"] = json!(false);
            value["error"] = Value::Null;
        }
        Err(e) => {
            value["conflict"] = json!(matches!(e, CommissionError::Conflict { .. }));
            value["error"] = json!(e.to_string());
        }
    }
    value
}

const TABLE_HEADER: &str = "address  firmware  status            angle  touch  counter";

fn found_line(found: &Found, ctx: &Ctx<'_>) -> String {
    match &found.answer {
        Ok(s) => {
            let mut notes = Vec::new();
            if !s.version_matches() {
                let (major, minor) = antenna_protocol::FIRMWARE_VERSION;
                notes.push(format!("this host speaks firmware {major}.{minor}"));
            }
            if s.unassigned() {
                notes.push(format!(
                    "unassigned: `antenna segments assign {} <ADDR>`",
                    hex(found.address)
                ));
            } else if ctx.config.is_some() && !ctx.configured(found.address) {
                notes.push("not in the configuration".to_owned());
            }
            format!(
                "{:<8} {:<9} {:<17} {:>5}  {:04b}  {:>7}{}",
                hex(found.address),
                format!("{}.{}", s.version.0, s.version.1),
                flag_names(s),
                s.word.angle_counts(),
                s.word.touch().bits(),
                s.counter,
                if notes.is_empty() {
                    String::new()
                } else {
                    format!("  ({})", notes.join("; "))
                }
            )
        }
        Err(CommissionError::Conflict { .. }) => format!(
            "{:<8} CONFLICT: more than one segment answers at {} (its reads fail their PEC; \
             connect the segments one at a time to assign them)",
            hex(found.address),
            hex(found.address)
        ),
        Err(e) => format!("{:<8} ERROR: {e}", hex(found.address)),
    }
}

fn bus_failure(ctx: &Ctx<'_>, e: CommissionError) -> Failure {
    Failure::NoSuccess(Some(anyhow!("{}: {e}", ctx.name)))
}

fn scan<I: I2c>(
    args: &ScanArgs,
    ctx: &Ctx<'_>,
    bus: &mut I,
    out: &mut dyn Write,
) -> Result<(), Failure> {
    if args.from > args.to {
        return bail_input(format!(
            "--from {} is above --to {}",
            hex(args.from),
            hex(args.to)
        ));
    }
    let found = commission::scan(bus, args.from..=args.to).map_err(|e| bus_failure(ctx, e))?;
    let missing: Vec<u8> = ctx
        .config
        .map(|c| c.addresses())
        .unwrap_or_default()
        .into_iter()
        .filter(|a| (args.from..=args.to).contains(a) && !found.iter().any(|f| f.address == *a))
        .collect();
    if ctx.json {
        return print_json(
            out,
            &json!({
                "bus": ctx.name,
                "from": args.from,
                "to": args.to,
                "found": found.iter().map(|f| found_json(f, ctx)).collect::<Vec<_>>(),
                "configured_missing": missing.iter().map(|&a| hex(a)).collect::<Vec<_>>(),
            }),
        );
    }
    say!(
        out,
        "{}: {} address{} answer{} in {}..={}",
        ctx.name,
        found.len(),
        if found.len() == 1 { "" } else { "es" },
        if found.len() == 1 { "s" } else { "" },
        hex(args.from),
        hex(args.to)
    );
    if !found.is_empty() {
        say!(out, "{TABLE_HEADER}");
    }
    for f in &found {
        say!(out, "{}", found_line(f, ctx));
    }
    if !missing.is_empty() {
        let list: Vec<String> = missing.iter().map(|&a| hex(a)).collect();
        say!(out, "configured but not answering: {}", list.join(", "));
    }
    Ok(())
}

fn assign<I: I2c>(
    args: &AssignArgs,
    ctx: &Ctx<'_>,
    bus: &mut I,
    out: &mut dyn Write,
) -> Result<(), Failure> {
    let place = format!(
        "{}: assign {} -> {}",
        ctx.name,
        hex(args.from),
        hex(args.to)
    );
    let moved = commission::assign(bus, args.from, args.to, ASSIGN_SETTLE).map_err(|e| {
        let refused = matches!(
            e,
            CommissionError::OutOfRange { .. }
                | CommissionError::DefaultAddress
                | CommissionError::AddressTaken(_)
                | CommissionError::NoSegment(_)
                | CommissionError::Conflict { .. }
        );
        let e = anyhow!("{place}: {e}");
        if refused {
            Failure::BadInput(e.context("refused, nothing written"))
        } else {
            Failure::NoSuccess(Some(e))
        }
    })?;
    let found = Found {
        address: moved.address,
        answer: Ok(moved),
    };
    if ctx.json {
        let mut value = found_json(&found, ctx);
        value["from"] = json!(hex(args.from));
        return print_json(out, &value);
    }
    say!(
        out,
        "{}: the segment at {} now answers at {}",
        ctx.name,
        hex(args.from),
        hex(args.to)
    );
    say!(out, "{TABLE_HEADER}");
    say!(out, "{}", found_line(&found, ctx));
    if ctx.config.is_some() && !ctx.configured(args.to) {
        say!(
            out,
            "add it to the configuration: [[bus.segments]] address = {}",
            hex(args.to)
        );
    }
    Ok(())
}

fn status<I: I2c>(
    args: &StatusArgs,
    ctx: &Ctx<'_>,
    bus: &mut I,
    out: &mut dyn Write,
) -> Result<(), Failure> {
    let addresses = ctx.addresses(&args.addresses)?;
    let found = commission::status(bus, &addresses);
    let unhealthy = found
        .iter()
        .filter(|f| {
            f.answer
                .as_ref()
                .map_or(true, |s| s.flags.bits() != 0 || !s.version_matches())
        })
        .count();
    if ctx.json {
        print_json(
            out,
            &json!({
                "bus": ctx.name,
                "segments": found.iter().map(|f| found_json(f, ctx)).collect::<Vec<_>>(),
            }),
        )?;
    } else {
        say!(out, "{}: {} segment(s)", ctx.name, found.len());
        say!(out, "{TABLE_HEADER}");
        for f in &found {
            say!(out, "{}", found_line(f, ctx));
        }
    }
    if unhealthy == 0 {
        Ok(())
    } else {
        Err(Failure::NoSuccess(Some(anyhow!(
            "{}: {unhealthy} of {} segment(s) missing, in conflict or with a status flag set",
            ctx.name,
            found.len()
        ))))
    }
}

fn zero<I: I2c>(
    args: &ZeroArgs,
    ctx: &Ctx<'_>,
    bus: &mut I,
    between: &mut dyn FnMut(&mut I),
    out: &mut dyn Write,
) -> Result<(), Failure> {
    let addresses = ctx.addresses(&args.addresses)?;
    // Everything about the output is checked before the measurement.
    let target = match (&args.output, ctx.config) {
        (Some(output), Some(_)) => {
            let input = bus_config_path(args)?;
            check_output(input, output, args.force)?;
            let text = std::fs::read_to_string(input)
                .with_context(|| format!("{}: cannot read", input.display()))?;
            let document: toml_edit::DocumentMut = text
                .parse()
                .with_context(|| format!("{}: not TOML", input.display()))?;
            for &address in &addresses {
                if !ctx.configured(address) {
                    return bail_input(format!(
                        "{}: {} is not one of its [[bus.segments]]: add it before writing its \
                         zero_counts",
                        input.display(),
                        hex(address)
                    ));
                }
            }
            Some((input, output, document))
        }
        _ => None,
    };
    let samples = usize::try_from(args.samples).unwrap_or(usize::MAX);
    let measured = commission::measure_zero_counts(bus, &addresses, samples, between)
        .map_err(|e| bus_failure(ctx, e))?;
    let previous = |address: u8| {
        ctx.config.and_then(|c| {
            c.segments
                .iter()
                .find(|s| s.address == address)
                .map(|s| s.zero_counts)
        })
    };
    let not_at_rest: Vec<String> = measured
        .iter()
        .filter_map(|m| {
            if m.flags.adc_fault() {
                Some(format!(
                    "{}: its angle sensor reports an ADC fault (its counts mean nothing)",
                    hex(m.address)
                ))
            } else if m.touched {
                Some(format!(
                    "{}: its touch switches closed: the joint is touching something, not at \
                     rest",
                    hex(m.address)
                ))
            } else {
                None
            }
        })
        .collect();
    if ctx.json {
        let rows: Vec<Value> = measured
            .iter()
            .map(|m| zero_json(m, previous(m.address)))
            .collect();
        print_json(
            out,
            &json!({
                "bus": ctx.name,
                "samples": samples,
                "segments": rows,
                "written": if not_at_rest.is_empty() {
                    target.as_ref().map(|t| t.1.display().to_string())
                } else {
                    None
                },
            }),
        )?;
    } else {
        say!(
            out,
            "{}: zero_counts of {} joint(s), circular mean of {samples} readings each",
            ctx.name,
            measured.len()
        );
        say!(
            out,
            "address  zero_counts  configured  max_deviation_counts"
        );
        for m in &measured {
            say!(
                out,
                "{:<8} {:>11}  {:>10}  {:>20}",
                hex(m.address),
                m.zero_counts,
                previous(m.address).map_or("-".to_owned(), |z| z.to_string()),
                m.max_deviation_counts
            );
        }
    }
    if !not_at_rest.is_empty() {
        return Err(Failure::NoSuccess(Some(anyhow!(
            "{}: not measured at rest, nothing written: {}",
            ctx.name,
            not_at_rest.join("; ")
        ))));
    }
    if let Some((input, output, mut document)) = target {
        set_zero_counts(&mut document, &measured)
            .with_context(|| format!("{}: [[bus.segments]]", input.display()))?;
        let text = document.to_string();
        let written = Config::from_toml_str(&text, &output.display().to_string())
            .context("the written configuration does not read back")?;
        for m in &measured {
            let back = written
                .segments
                .iter()
                .find(|s| s.address == m.address)
                .map(|s| s.zero_counts);
            if back != Some(m.zero_counts) {
                return Err(Failure::NoSuccess(Some(anyhow!(
                    "{}: the written copy reads zero_counts {back:?} for {:#04x}, measured {}; \
                     nothing written",
                    output.display(),
                    m.address,
                    m.zero_counts
                ))));
            }
        }
        std::fs::write(output, text)
            .with_context(|| format!("{}: cannot write", output.display()))?;
        if !ctx.json {
            say!(
                out,
                "wrote {} (a copy of {} with these zero_counts)",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}

fn bus_config_path(args: &ZeroArgs) -> Result<&Path, Failure> {
    match &args.bus.config {
        Some(path) => Ok(path),
        None => bail_input("-o needs --config: the file the copy is made from".to_owned()),
    }
}

/// The output may not be the input, nor replace a file without --force.
fn check_output(input: &Path, output: &Path, force: bool) -> Result<(), Failure> {
    let same = match (input.canonicalize(), output.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => input == output,
    };
    if same {
        return bail_input(format!(
            "-o {}: that is the --config file itself; write a copy and compare it first",
            output.display()
        ));
    }
    if output.exists() && !force {
        return bail_input(format!(
            "-o {}: the file exists (--force replaces it)",
            output.display()
        ));
    }
    Ok(())
}

fn zero_json(m: &ZeroMeasurement, previous: Option<u16>) -> Value {
    json!({
        "address": m.address,
        "address_hex": hex(m.address),
        "zero_counts": m.zero_counts,
        "configured_zero_counts": previous,
        "samples": m.samples,
        "max_deviation_counts": m.max_deviation_counts,
        "touched": m.touched,
        "adc_fault": m.flags.adc_fault(),
    })
}

/// Writes each measurement's `zero_counts` into its `[[bus.segments]]` entry (array of
/// tables or inline tables), keeping everything else as it was.
fn set_zero_counts(
    document: &mut toml_edit::DocumentMut,
    measured: &[ZeroMeasurement],
) -> anyhow::Result<()> {
    let segments = document
        .get_mut("bus")
        .and_then(|bus| bus.get_mut("segments"))
        .ok_or_else(|| anyhow!("no [[bus.segments]] in the file"))?;
    for m in measured {
        let value = i64::from(m.zero_counts);
        let address = i64::from(m.address);
        let done = if let Some(tables) = segments.as_array_of_tables_mut() {
            tables
                .iter_mut()
                .find(|t| t.get("address").and_then(|a| a.as_integer()) == Some(address))
                .and_then(|t| t.get_mut("zero_counts"))
                .and_then(|item| item.as_value_mut())
                .map(|v| replace_keeping_decor(v, value))
                .is_some()
        } else if let Some(array) = segments.as_array_mut() {
            array
                .iter_mut()
                .filter_map(|v| v.as_inline_table_mut())
                .find(|t| t.get("address").and_then(|a| a.as_integer()) == Some(address))
                .and_then(|t| t.get_mut("zero_counts"))
                .map(|v| replace_keeping_decor(v, value))
                .is_some()
        } else {
            false
        };
        if !done {
            return Err(anyhow!("no entry with address = {}", hex(m.address)));
        }
    }
    Ok(())
}

/// Replaces an integer, keeping the white space and comment around it.
fn replace_keeping_decor(slot: &mut toml_edit::Value, value: i64) {
    let decor = slot.decor().clone();
    *slot = value.into();
    *slot.decor_mut() = decor;
}
