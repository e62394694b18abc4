//! The loopback wiring of rackcat's default rack (examples/default-rack.yaml, docs/MDP.md)
//! and its translation into bit offsets of the process image ethercrab maps.
//!
//! Default rack (docs/MDP.md "Module numbering": modules are the populated slots, RIM by
//! RIM, slot by slot; outputs 0x7000 + (n-1)·0x10 + X, inputs 0x6000 + (n-1)·0x10 + X):
//! - RIM 1 slot 1 CDO-10 (module 1, DOUTx16 0x7000:01) -> RIM 1 slot 2 CDI-10 (module 2,
//!   DINx16 0x6010:01), `loopback: {rim: 1, slot: 1}`: channel i reads output channel i, all 16.
//! - RIM 2 slot 7 CDO-10 (module 26, 0x7190:01) -> RIM 2 slot 8 CDI-10 (module 27, 0x61A0:01),
//!   channels 0 and 1 only (per-channel `source: loopback`).
//!
//! The analogue pair (CAO-15 -> CAI-11) is not checked: its values pass through a DAC/ADC
//! model, not bit for bit.

use crate::loopback::Wire;

/// One PDO entry as mapped (index, subindex, bit length), in mapping order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MappedEntry {
    pub index: u16,
    pub sub: u8,
    pub bits: u8,
}

impl MappedEntry {
    /// Decodes a mapping entry value (ETG.1000.6 Table 74: index << 16 | sub << 8 | bits).
    pub fn from_raw(v: u32) -> Self {
        MappedEntry {
            index: (v >> 16) as u16,
            sub: ((v >> 8) & 0xFF) as u8,
            bits: (v & 0xFF) as u8,
        }
    }
}

/// The process image layout one SubDevice announced through 0x1C12/0x1C13 and the mapping
/// objects: entries follow each other without gaps, as ethercrab lays them out.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PdoLayout {
    pub outputs: Vec<MappedEntry>,
    pub inputs: Vec<MappedEntry>,
}

fn bit_offset(entries: &[MappedEntry], index: u16, sub: u8) -> Option<(usize, u8)> {
    let mut offset = 0usize;
    for e in entries {
        if e.index == index && e.sub == sub {
            return Some((offset, e.bits));
        }
        offset += usize::from(e.bits);
    }
    None
}

impl PdoLayout {
    pub fn output_bits(&self) -> usize {
        self.outputs.iter().map(|e| usize::from(e.bits)).sum()
    }
    pub fn input_bits(&self) -> usize {
        self.inputs.iter().map(|e| usize::from(e.bits)).sum()
    }
}

/// A channel-for-channel connection between an output object and an input object.
#[derive(Debug, Clone, Copy)]
pub struct ObjectLoop {
    pub what: &'static str,
    pub out_index: u16,
    pub out_sub: u8,
    pub in_index: u16,
    pub in_sub: u8,
    pub channels: u8,
}

pub const DEFAULT_RACK_LOOPS: [ObjectLoop; 2] = [
    ObjectLoop {
        what: "RIM 1 slot 1 CDO-10 -> slot 2 CDI-10",
        out_index: 0x7000,
        out_sub: 1,
        in_index: 0x6010,
        in_sub: 1,
        channels: 16,
    },
    ObjectLoop {
        what: "RIM 2 slot 7 CDO-10 ch 0-1 -> slot 8 CDI-10 ch 0-1",
        out_index: 0x7190,
        out_sub: 1,
        in_index: 0x61A0,
        in_sub: 1,
        channels: 2,
    },
];

/// Turns object loops into image bit wires; loops whose objects are not mapped are
/// reported in the second value.
pub fn wires_from_layout(layout: &PdoLayout, loops: &[ObjectLoop]) -> (Vec<Wire>, Vec<String>) {
    let mut wires = Vec::new();
    let mut problems = Vec::new();
    for l in loops {
        let out = bit_offset(&layout.outputs, l.out_index, l.out_sub);
        let inp = bit_offset(&layout.inputs, l.in_index, l.in_sub);
        match (out, inp) {
            (Some((ob, obits)), Some((ib, ibits))) => {
                let n = l.channels.min(obits).min(ibits);
                if n < l.channels {
                    problems.push(format!(
                        "{}: only {n} of {} channels mapped ({obits} output bits, {ibits} input bits)",
                        l.what, l.channels
                    ));
                }
                for ch in 0..usize::from(n) {
                    wires.push(Wire {
                        out_bit: ob + ch,
                        in_bit: ib + ch,
                    });
                }
            }
            _ => problems.push(format!(
                "{}: {:#06x}:{:02x} mapped as output: {}, {:#06x}:{:02x} mapped as input: {}",
                l.what,
                l.out_index,
                l.out_sub,
                out.is_some(),
                l.in_index,
                l.in_sub,
                inp.is_some()
            )),
        }
    }
    (wires, problems)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapping_entries_decode_per_etg1000_6() {
        let e = MappedEntry::from_raw(0x7000_0110);
        assert_eq!(
            e,
            MappedEntry {
                index: 0x7000,
                sub: 1,
                bits: 16
            }
        );
    }

    #[test]
    fn wires_follow_the_mapping_order() {
        let layout = PdoLayout {
            outputs: vec![
                MappedEntry::from_raw(0x7000_0110),
                MappedEntry::from_raw(0x7021_0108),
                MappedEntry::from_raw(0x7190_0110),
            ],
            inputs: vec![
                MappedEntry::from_raw(0x6010_0110),
                MappedEntry::from_raw(0x61A0_0110),
            ],
        };
        let (wires, problems) = wires_from_layout(&layout, &DEFAULT_RACK_LOOPS);
        assert!(problems.is_empty(), "{problems:?}");
        assert_eq!(wires.len(), 18);
        assert_eq!(
            wires[0],
            Wire {
                out_bit: 0,
                in_bit: 0
            }
        );
        assert_eq!(
            wires[15],
            Wire {
                out_bit: 15,
                in_bit: 15
            }
        );
        // 0x7190 starts after 16 + 8 output bits, 0x61A0 after 16 input bits
        assert_eq!(
            wires[16],
            Wire {
                out_bit: 24,
                in_bit: 16
            }
        );
        assert_eq!(
            wires[17],
            Wire {
                out_bit: 25,
                in_bit: 17
            }
        );
        assert_eq!(layout.output_bits(), 40);
    }

    #[test]
    fn unmapped_loops_are_reported_not_guessed() {
        let layout = PdoLayout {
            outputs: vec![MappedEntry::from_raw(0x7000_0110)],
            inputs: vec![],
        };
        let (wires, problems) = wires_from_layout(&layout, &DEFAULT_RACK_LOOPS);
        assert!(wires.is_empty());
        assert_eq!(problems.len(), 2);
    }
}
