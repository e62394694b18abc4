//! Command-line options. Hand-parsed to keep the dependency set to ethercrab itself.

use crate::loopback::Wire;
use std::time::Duration;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// `ecat_wire_slave`: no mailbox, the whole output image is echoed on the inputs.
    TestSlave,
    /// `rackcat run`: CoE, SDO information, loopback-wired DO -> DI channels.
    Rackcat,
    /// `rackcat run --line`: devices of any kind (no CoE checks, no SM/FMMU demands beyond
    /// what each device's SII lists); `--wire` offsets are bits of the concatenated output
    /// and input images of all SubDevices in line order, so a wire may cross devices.
    Line,
    /// A configurator for benchmarks (op.rs): a line of any length up to 4,096 to OP with the
    /// process-data watchdog off, `--cycles` cycles, then exit leaving it in OP.
    Op,
}

#[derive(Debug, Clone)]
pub struct Options {
    pub iface: String,
    pub expect_slaves: Option<usize>,
    pub cycles: u64,
    pub mode: Mode,
    pub cycle_time: Duration,
    /// Cycles an output pattern is held before its echo must be on the inputs.
    pub hold_cycles: u64,
    /// Explicit loopback wiring (output bit -> input bit within one SubDevice's image);
    /// empty means the mode's default.
    pub wires: Vec<Wire>,
    pub sync0: bool,
    /// Use ethercrab's blocking `into_op` (no process data until OP) instead of
    /// `request_into_op` plus cycling.
    pub blocking_op: bool,
    pub expect_vendor: Option<u32>,
    pub expect_product: Option<u32>,
    /// Line mode: the product code of every SubDevice, in line order.
    pub expect_products: Vec<u32>,
    /// Writable string object exercised with normal and segmented SDO downloads.
    pub string_object: (u16, u8),
    pub string_value: String,
    /// Value written with the segmented download (must differ from `string_value`).
    pub string_value_segmented: String,
    /// Writable object of at most 4 bytes exercised with an expedited download.
    pub u32_object: (u16, u8),
    pub verbose: bool,
}

pub const USAGE: &str = "\
usage: ethercrab-interop --iface IFACE [options]
  --iface IFACE            network interface (raw socket; needs CAP_NET_RAW)
  --expect-slaves N        fail unless exactly N SubDevices answer
  --cycles N               process-data cycles in OP (default 10000)
  --mode testslave|rackcat|line|op
                           testslave: no CoE, whole output image echoed on inputs;
                           rackcat: CoE/SDO info checks, loopback-wired DO->DI (default);
                           line: devices of any kind (rackcat run --line), --wire offsets
                           in the concatenated images of all SubDevices (cross-device wires);
                           op: a benchmark's configurator: up to 4,096 SubDevices to OP with
                           the process-data watchdog off, --cycles cycles (working counter
                           checked), one `op:` line with the image, exit leaving them in OP
  --expect-products P,P,.. product code of each SubDevice in order (0x.. for hex)
  --cycle-us N             cycle period in microseconds (default 1000)
  --hold N                 cycles each output pattern is held (default 4); the echo must
                           be on the inputs by the last cycle of the hold
  --wire OUT:IN[,OUT:IN]   loopback wiring as bit offsets in the SubDevice's output and
                           input images, e.g. 0:0,1:1 or byte.bit form 2.0:6.0
  --no-sync0               keep DC static drift compensation but do not start SYNC0
  --blocking-op            with --no-sync0: go to OP with ethercrab's into_op (AL status
                           polled, no process data until OP), as its examples do
  --expect-vendor N        expected vendor id, 0x.. for hex (checked against the SII identity,
                           which 0x1018 must match)
  --expect-product N       expected product code, likewise
  --string-object IDX:SUB  writable string for normal/segmented downloads (default 0x2000:04)
  --string-value TEXT      value written there with a normal download (default 10.11.12.13)
  --string-value-segmented TEXT
                           value written with a segmented download (default 10.21.32.43);
                           the original value is restored afterwards
  --u32-object IDX:SUB     writable 32-bit object for expedited download (default 0x2000:09)
  -v, --verbose            print every check, not only failures
Environment: RUST_LOG=error|warn|info|debug|trace shows ethercrab's own log (default warn).
";

fn parse_u32(text: &str) -> Result<u32, String> {
    let t = text.trim();
    let r = if let Some(hex) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        u32::from_str_radix(hex, 16)
    } else {
        t.parse::<u32>()
    };
    r.map_err(|_| format!("not a number: {text}"))
}

fn parse_object(text: &str) -> Result<(u16, u8), String> {
    let (i, s) = text
        .split_once(':')
        .ok_or_else(|| format!("expected INDEX:SUBINDEX, got {text}"))?;
    let index = u16::try_from(parse_u32(i)?).map_err(|_| format!("index too big: {i}"))?;
    let sub = u8::try_from(parse_u32(s)?).map_err(|_| format!("subindex too big: {s}"))?;
    Ok((index, sub))
}

/// A bit position given either as a plain bit offset (`13`) or as `byte.bit` (`1.5`).
fn parse_bit(text: &str) -> Result<usize, String> {
    match text.split_once('.') {
        Some((byte, bit)) => {
            let byte = parse_u32(byte)? as usize;
            let bit = parse_u32(bit)? as usize;
            if bit > 7 {
                return Err(format!("bit number above 7 in {text}"));
            }
            Ok(byte * 8 + bit)
        }
        None => Ok(parse_u32(text)? as usize),
    }
}

pub fn parse_wires(text: &str) -> Result<Vec<Wire>, String> {
    text.split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|pair| {
            let (o, i) = pair
                .split_once(':')
                .ok_or_else(|| format!("expected OUT:IN, got {pair}"))?;
            Ok(Wire {
                out_bit: parse_bit(o)?,
                in_bit: parse_bit(i)?,
            })
        })
        .collect()
}

impl Options {
    pub fn parse(args: impl IntoIterator<Item = String>) -> Result<Options, String> {
        let mut o = Options {
            iface: String::new(),
            expect_slaves: None,
            cycles: 10_000,
            mode: Mode::Rackcat,
            cycle_time: Duration::from_micros(1000),
            hold_cycles: 4,
            wires: Vec::new(),
            sync0: true,
            blocking_op: false,
            expect_vendor: None,
            expect_product: None,
            expect_products: Vec::new(),
            string_object: (0x2000, 0x04),
            string_value: "10.11.12.13".to_string(),
            string_value_segmented: "10.21.32.43".to_string(),
            u32_object: (0x2000, 0x09),
            verbose: false,
        };
        let mut it = args.into_iter();
        while let Some(arg) = it.next() {
            let mut value = |name: &str| it.next().ok_or_else(|| format!("{name} needs a value"));
            match arg.as_str() {
                "--iface" | "-i" => o.iface = value(&arg)?,
                "--expect-slaves" => o.expect_slaves = Some(parse_u32(&value(&arg)?)? as usize),
                "--cycles" => o.cycles = u64::from(parse_u32(&value(&arg)?)?),
                "--mode" => {
                    o.mode = match value(&arg)?.as_str() {
                        "testslave" => Mode::TestSlave,
                        "rackcat" => Mode::Rackcat,
                        "line" => Mode::Line,
                        "op" => Mode::Op,
                        m => return Err(format!("unknown mode {m} (testslave|rackcat|line|op)")),
                    }
                }
                "--cycle-us" => {
                    o.cycle_time = Duration::from_micros(u64::from(parse_u32(&value(&arg)?)?))
                }
                "--hold" => {
                    o.hold_cycles = u64::from(parse_u32(&value(&arg)?)?).max(2);
                }
                "--wire" => o.wires = parse_wires(&value(&arg)?)?,
                "--no-sync0" => o.sync0 = false,
                "--blocking-op" => o.blocking_op = true,
                "--expect-vendor" => o.expect_vendor = Some(parse_u32(&value(&arg)?)?),
                "--expect-product" => o.expect_product = Some(parse_u32(&value(&arg)?)?),
                "--expect-products" => {
                    o.expect_products = value(&arg)?
                        .split(',')
                        .map(parse_u32)
                        .collect::<Result<Vec<_>, _>>()?
                }
                "--string-object" => o.string_object = parse_object(&value(&arg)?)?,
                "--string-value" => o.string_value = value(&arg)?,
                "--string-value-segmented" => o.string_value_segmented = value(&arg)?,
                "--u32-object" => o.u32_object = parse_object(&value(&arg)?)?,
                "-v" | "--verbose" => o.verbose = true,
                "-h" | "--help" => return Err(String::new()),
                other => return Err(format!("unknown argument {other}")),
            }
        }
        if o.iface.is_empty() {
            return Err("--iface is required".to_string());
        }
        if o.string_value == o.string_value_segmented {
            return Err(
                "the two string values must differ, or a failed write goes unseen".to_string(),
            );
        }
        if o.blocking_op && o.sync0 {
            return Err(
                "--blocking-op needs --no-sync0 (with SYNC0 OP is requested, then cycled)"
                    .to_string(),
            );
        }
        if o.cycle_time.is_zero() {
            return Err("--cycle-us must be above 0".to_string());
        }
        Ok(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn defaults_match_the_issue() {
        let o = Options::parse(args(&["--iface", "veth1"])).unwrap();
        assert_eq!(o.cycles, 10_000);
        assert_eq!(o.mode, Mode::Rackcat);
        assert_eq!(o.string_object, (0x2000, 4));
        assert!(o.sync0);
    }

    #[test]
    fn wires_accept_bit_offsets_and_byte_dot_bit() {
        let w = parse_wires("0:0,2.1:6.7").unwrap();
        assert_eq!(
            w[0],
            Wire {
                out_bit: 0,
                in_bit: 0
            }
        );
        assert_eq!(
            w[1],
            Wire {
                out_bit: 17,
                in_bit: 55
            }
        );
        assert!(parse_wires("1.8:0").is_err());
        assert!(parse_wires("3").is_err());
    }

    #[test]
    fn objects_parse_hex_and_decimal() {
        assert_eq!(parse_object("0x2000:4").unwrap(), (0x2000, 4));
        assert_eq!(parse_object("4096:0x0a").unwrap(), (0x1000, 10));
        assert!(parse_object("0x12345:0").is_err());
    }

    #[test]
    fn op_mode_is_the_benchmark_configurator() {
        let o = Options::parse(args(&["--iface", "x", "--mode", "op", "--cycles", "300"])).unwrap();
        assert_eq!(o.mode, Mode::Op);
        assert_eq!(o.cycles, 300);
    }

    #[test]
    fn missing_iface_is_an_error() {
        assert!(Options::parse(args(&["--cycles", "5"])).is_err());
        assert!(Options::parse(args(&["--iface"])).is_err());
        assert!(Options::parse(args(&["--iface", "x", "--mode", "soem"])).is_err());
    }
}
