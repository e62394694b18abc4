//! Checks that outputs written through the process data come back on the inputs.
//!
//! Each SubDevice gets a set of wires (output bit -> input bit, offsets within that
//! SubDevice's own output and input images). The checker drives a new pseudo-random
//! pattern onto the wired output bits every `hold` cycles (always different from the
//! previous one) and, every cycle, reads the wired input bits:
//! - before the echo of the new pattern arrives, the inputs may still show the previous
//!   pattern (the slave's application copies outputs to inputs after the frame, so one
//!   or more cycles of lag are normal);
//! - once the new pattern was seen it must stay (a return to the old one is a glitch);
//! - anything else is a mismatch, and so is a window whose echo never arrived.
//!
//! The lag (cycles from writing a pattern to seeing it) is recorded as a histogram.

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Wire {
    pub out_bit: usize,
    pub in_bit: usize,
}

pub fn get_bit(buf: &[u8], bit: usize) -> bool {
    buf.get(bit / 8).is_some_and(|b| b & (1 << (bit % 8)) != 0)
}

pub fn set_bit(buf: &mut [u8], bit: usize, value: bool) {
    if let Some(b) = buf.get_mut(bit / 8) {
        if value {
            *b |= 1 << (bit % 8);
        } else {
            *b &= !(1 << (bit % 8));
        }
    }
}

/// Wires every bit of the shorter image to the same bit of the other: the test slave's
/// application copies its whole output image to its input image.
pub fn identity_wires(out_len: usize, in_len: usize) -> Vec<Wire> {
    (0..8 * out_len.min(in_len))
        .map(|b| Wire {
            out_bit: b,
            in_bit: b,
        })
        .collect()
}

/// Checks the wires against the image sizes; returns what does not fit.
pub fn validate_wires(wires: &[Wire], out_len: usize, in_len: usize) -> Result<(), String> {
    for w in wires {
        if w.out_bit >= out_len * 8 {
            return Err(format!(
                "wire output bit {} ({}.{}) is outside the {}-byte output image",
                w.out_bit,
                w.out_bit / 8,
                w.out_bit % 8,
                out_len
            ));
        }
        if w.in_bit >= in_len * 8 {
            return Err(format!(
                "wire input bit {} ({}.{}) is outside the {}-byte input image",
                w.in_bit,
                w.in_bit / 8,
                w.in_bit % 8,
                in_len
            ));
        }
    }
    Ok(())
}

/// The LRW working counter ethercrab's `tx_rx` returns: the sum over the frames the group
/// image is cut into. ethercrab lays the image out as all SubDevices' inputs, then all their
/// outputs (byte aligned, in SubDevice order), and sends it in LRW datagrams of `chunk` bytes,
/// the first one `first_chunk` bytes (shorter when a DC FRMW shares the first frame).
/// Per datagram each SubDevice adds 1 when its input FMMU is hit and 2 when its output FMMU is
/// (ETG.1000.4 §5.4.4, LRW), so a SubDevice whose area straddles two datagrams counts twice.
pub fn expected_lrw_wkc(
    in_lens: &[usize],
    out_lens: &[usize],
    first_chunk: usize,
    chunk: usize,
) -> u16 {
    let mut areas: Vec<(usize, usize, u16)> = Vec::new();
    let mut at = 0usize;
    for &len in in_lens {
        areas.push((at, at + len, 1));
        at += len;
    }
    for &len in out_lens {
        areas.push((at, at + len, 2));
        at += len;
    }
    let total = at;
    let mut wkc = 0u16;
    let mut start = 0usize;
    while start < total {
        let len = if start == 0 { first_chunk } else { chunk }.max(1);
        let end = (start + len).min(total);
        for &(a, b, inc) in &areas {
            if a < b && a < end && start < b {
                wkc += inc;
            }
        }
        start = end;
    }
    wkc
}

const MAX_REPORTED: usize = 5;
pub const LAG_BUCKETS: usize = 16;

pub struct LoopbackCheck {
    wires: Vec<Wire>,
    hold: u64,
    rng: u64,
    current: Vec<bool>,
    previous: Vec<bool>,
    observed: Vec<bool>,
    window: u64,
    cycle_in_window: u64,
    seen_current: bool,
    pub lag_histogram: [u64; LAG_BUCKETS],
    pub windows_checked: u64,
    pub mismatches: u64,
    pub failures: Vec<String>,
}

fn bits_text(bits: &[bool]) -> String {
    let shown: String = bits
        .iter()
        .take(64)
        .map(|&b| if b { '1' } else { '0' })
        .collect();
    if bits.len() > 64 {
        format!("{shown}... ({} bits)", bits.len())
    } else {
        shown
    }
}

impl LoopbackCheck {
    pub fn new(wires: Vec<Wire>, hold: u64, seed: u64) -> Self {
        let n = wires.len();
        LoopbackCheck {
            wires,
            hold: hold.max(2),
            // xorshift must not start at zero
            rng: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1,
            current: vec![false; n],
            previous: vec![false; n],
            observed: vec![false; n],
            window: 0,
            cycle_in_window: 0,
            seen_current: false,
            lag_histogram: [0; LAG_BUCKETS],
            windows_checked: 0,
            mismatches: 0,
            failures: Vec::new(),
        }
    }

    pub fn wire_count(&self) -> usize {
        self.wires.len()
    }

    fn next_random(&mut self) -> u64 {
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.rng = x;
        x
    }

    fn fail(&mut self, text: String) {
        self.mismatches += 1;
        if self.failures.len() < MAX_REPORTED {
            self.failures.push(text);
        }
    }

    /// Writes this cycle's pattern onto the wired output bits (call before the exchange).
    pub fn drive(&mut self, outputs: &mut [u8]) {
        if self.wires.is_empty() {
            return;
        }
        if self.cycle_in_window == 0 {
            std::mem::swap(&mut self.previous, &mut self.current);
            let mut word = 0u64;
            for i in 0..self.current.len() {
                if i % 64 == 0 {
                    word = self.next_random();
                }
                self.current[i] = (word >> (i % 64)) & 1 != 0;
            }
            // A new pattern must differ from the previous one, or a stuck input would pass.
            if self.current == self.previous {
                self.current[0] = !self.current[0];
            }
            self.seen_current = false;
        }
        for (w, &v) in self.wires.iter().zip(&self.current) {
            set_bit(outputs, w.out_bit, v);
        }
    }

    /// Checks the inputs read back by the exchange of cycle `cycle`.
    pub fn observe(&mut self, inputs: &[u8], cycle: u64) {
        if self.wires.is_empty() {
            return;
        }
        for (i, w) in self.wires.iter().enumerate() {
            self.observed[i] = get_bit(inputs, w.in_bit);
        }
        if self.observed == self.current {
            if !self.seen_current {
                self.seen_current = true;
                let bucket = (self.cycle_in_window as usize).min(LAG_BUCKETS - 1);
                self.lag_histogram[bucket] += 1;
            }
        } else if self.seen_current {
            let text = format!(
                "cycle {cycle}: inputs changed after the echo arrived: expected {} got {}",
                bits_text(&self.current),
                bits_text(&self.observed)
            );
            self.fail(text);
        } else if self.window > 0 && self.observed != self.previous {
            let text = format!(
                "cycle {cycle}: inputs {} are neither the new pattern {} nor the previous {}",
                bits_text(&self.observed),
                bits_text(&self.current),
                bits_text(&self.previous)
            );
            self.fail(text);
        }
        self.cycle_in_window += 1;
        if self.cycle_in_window == self.hold {
            self.windows_checked += 1;
            if !self.seen_current {
                let text = format!(
                    "cycle {cycle}: pattern {} written {} cycles ago never came back (inputs {})",
                    bits_text(&self.current),
                    self.hold,
                    bits_text(&self.observed)
                );
                self.fail(text);
            }
            self.cycle_in_window = 0;
            self.window += 1;
        }
    }

    pub fn lag_text(&self) -> String {
        self.lag_histogram
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(lag, n)| format!("lag {lag}: {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A simulated slave that shows the outputs on its inputs `lag` exchanges later.
    fn run(check: &mut LoopbackCheck, cycles: u64, lag: usize, corrupt_at: Option<u64>) {
        let mut history: Vec<Vec<u8>> = Vec::new();
        let mut outputs = vec![0u8; 4];
        for cycle in 0..cycles {
            check.drive(&mut outputs);
            history.push(outputs.clone());
            let mut inputs = if history.len() > lag {
                history[history.len() - 1 - lag].clone()
            } else {
                vec![0u8; 4]
            };
            if corrupt_at == Some(cycle) {
                inputs[0] ^= 0xFF;
            }
            check.observe(&inputs, cycle);
        }
    }

    #[test]
    fn echo_with_lag_one_passes_and_is_measured() {
        let mut c = LoopbackCheck::new(identity_wires(4, 4), 4, 1);
        run(&mut c, 400, 1, None);
        assert_eq!(c.mismatches, 0, "{:?}", c.failures);
        assert_eq!(c.windows_checked, 100);
        assert_eq!(c.lag_histogram[1], 100);
    }

    #[test]
    fn echo_slower_than_the_hold_fails() {
        let mut c = LoopbackCheck::new(identity_wires(4, 4), 4, 1);
        run(&mut c, 40, 4, None);
        assert!(c.mismatches > 0);
    }

    #[test]
    fn a_corrupted_input_is_reported() {
        let mut c = LoopbackCheck::new(identity_wires(4, 4), 4, 7);
        run(&mut c, 100, 1, Some(50));
        assert!(c.mismatches >= 1);
        assert!(c.failures[0].contains("cycle 50"), "{:?}", c.failures);
    }

    #[test]
    fn a_stuck_single_wire_is_caught() {
        // One wire whose input never changes: the pattern alternates, so the echo of
        // every other window is missing.
        let wires = vec![Wire {
            out_bit: 3,
            in_bit: 9,
        }];
        let mut c = LoopbackCheck::new(wires, 3, 5);
        let mut outputs = vec![0u8; 1];
        for cycle in 0..30 {
            c.drive(&mut outputs);
            c.observe(&[0u8, 0u8], cycle);
        }
        assert!(c.mismatches >= 4);
    }

    #[test]
    fn crossed_wires_are_followed() {
        let wires = vec![
            Wire {
                out_bit: 0,
                in_bit: 12,
            },
            Wire {
                out_bit: 1,
                in_bit: 8,
            },
        ];
        let mut c = LoopbackCheck::new(wires, 4, 3);
        let mut outputs = vec![0u8; 1];
        let mut inputs = vec![0u8; 2];
        for cycle in 0..100 {
            c.drive(&mut outputs);
            c.observe(&inputs, cycle);
            // the slave copies after the exchange: visible next cycle
            set_bit(&mut inputs, 12, get_bit(&outputs, 0));
            set_bit(&mut inputs, 8, get_bit(&outputs, 1));
        }
        assert_eq!(c.mismatches, 0, "{:?}", c.failures);
    }

    #[test]
    fn lrw_wkc_counts_each_datagram_an_area_touches() {
        // one frame: 2 per output area, 1 per input area, nothing for an empty area
        assert_eq!(expected_lrw_wkc(&[4], &[4], 1100, 1100), 3);
        assert_eq!(expected_lrw_wkc(&[4, 4], &[4, 0], 1100, 1100), 1 + 1 + 2);
        // inputs 0..600 and 600..1200, outputs 1200..1260 and 1260..1320, datagrams of 1000:
        // 0..1000 hits in0 and in1; 1000..1320 hits in1, out0 and out1
        assert_eq!(
            expected_lrw_wkc(&[600, 600], &[60, 60], 1000, 1000),
            1 + 1 + 1 + 2 + 2
        );
        // 16 default racks (548 input, 60 output bytes each): inputs end at 8768, the image
        // at 9728. Datagrams of 1100: cuts at 1100..7700 split 7 input areas, the cut at 8800
        // splits output area 0.
        assert_eq!(
            expected_lrw_wkc(&[548; 16], &[60; 16], 1100, 1100),
            16 + 7 + 32 + 2
        );
        // With DC the FRMW takes 20 bytes of the first frame, so datagrams are 1080, 1100, ..:
        // the cut at 5480 = 10 x 548 falls between two input areas, 6 input areas are split
        // and output area 0 is split at 8780. Seen on the wire with rackcat: 2,3,3,3,3,3,3,4,32.
        assert_eq!(
            expected_lrw_wkc(&[548; 16], &[60; 16], 1080, 1100),
            2 + 3 * 6 + 4 + 32
        );
        assert_eq!(expected_lrw_wkc(&[], &[], 1100, 1100), 0);
    }

    #[test]
    fn wires_outside_the_images_are_rejected() {
        let w = [Wire {
            out_bit: 16,
            in_bit: 0,
        }];
        assert!(validate_wires(&w, 2, 1).is_err());
        assert!(validate_wires(&w, 3, 1).is_ok());
        assert_eq!(identity_wires(2, 3).len(), 16);
    }
}
