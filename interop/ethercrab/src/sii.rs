//! Reads a SubDevice's SII (EEPROM) with ethercrab's EEPROM reader and decodes what the
//! checks need: the fixed header words (ETG.1000.6 Table 16 / ETG.2010 §2) and the
//! category list that starts at word 0x40 (ETG.1000.6 Table 17).

use ethercrab::{MainDevice, SubDevice, error::Error};

/// Category types (ETG.1000.6 Table 19).
pub const CAT_STRINGS: u16 = 10;
pub const CAT_GENERAL: u16 = 30;
pub const CAT_FMMU: u16 = 40;
pub const CAT_SYNCM: u16 = 41;
pub const CAT_TXPDO: u16 = 50;
pub const CAT_RXPDO: u16 = 51;
pub const CAT_DC: u16 = 60;
pub const CAT_END: u16 = 0xFFFF;

pub fn category_name(t: u16) -> &'static str {
    match t {
        CAT_STRINGS => "strings",
        20 => "datatypes",
        CAT_GENERAL => "general",
        CAT_FMMU => "FMMU",
        CAT_SYNCM => "SyncM",
        42 => "FMMUX",
        43 => "SyncUnit",
        CAT_TXPDO => "TxPDO",
        CAT_RXPDO => "RxPDO",
        CAT_DC => "DC",
        _ => "other",
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Category {
    pub kind: u16,
    /// Data start, in words.
    pub start_word: u16,
    pub len_words: u16,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncManagerEntry {
    pub start: u16,
    pub len: u16,
    pub control: u8,
    pub enable: u8,
    /// 1 mailbox out, 2 mailbox in, 3 process data out, 4 process data in.
    pub kind: u8,
}

#[derive(Debug, Clone, Default)]
pub struct SiiInfo {
    pub size_bytes: usize,
    pub header: Vec<u8>,
    pub categories: Vec<Category>,
    pub strings: Vec<String>,
    pub sync_managers: Vec<SyncManagerEntry>,
    pub fmmu_usage: Vec<u8>,
    /// General category byte 5 (CoE details) when present.
    pub coe_details: Option<u8>,
    pub general_name: Option<String>,
}

/// CRC-8 over the first 7 words (ETG.1000.6 §5.4, ETG.2010 Table 2): polynomial x^8+x^2+x+1,
/// initial value 0xFF, no reflection.
pub fn crc8(bytes: &[u8]) -> u8 {
    let mut crc = 0xFFu8;
    for &b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

fn word(buf: &[u8], w: usize) -> u16 {
    u16::from_le_bytes([buf[2 * w], buf[2 * w + 1]])
}

fn dword(buf: &[u8], w: usize) -> u32 {
    u32::from_le_bytes([buf[2 * w], buf[2 * w + 1], buf[2 * w + 2], buf[2 * w + 3]])
}

impl SiiInfo {
    pub fn vendor(&self) -> u32 {
        dword(&self.header, 0x08)
    }
    pub fn product(&self) -> u32 {
        dword(&self.header, 0x0A)
    }
    pub fn revision(&self) -> u32 {
        dword(&self.header, 0x0C)
    }
    pub fn serial(&self) -> u32 {
        dword(&self.header, 0x0E)
    }
    pub fn crc_stored(&self) -> u8 {
        self.header[14]
    }
    pub fn crc_computed(&self) -> u8 {
        crc8(&self.header[0..14])
    }
    /// (offset, size) of the receive (master -> slave) mailbox, words 0x18/0x19.
    pub fn rx_mailbox(&self) -> (u16, u16) {
        (word(&self.header, 0x18), word(&self.header, 0x19))
    }
    /// (offset, size) of the send (slave -> master) mailbox, words 0x1A/0x1B.
    pub fn tx_mailbox(&self) -> (u16, u16) {
        (word(&self.header, 0x1A), word(&self.header, 0x1B))
    }
    /// Mailbox protocols, word 0x1C (bit 2 = CoE).
    pub fn mailbox_protocols(&self) -> u16 {
        word(&self.header, 0x1C)
    }
    pub fn has(&self, kind: u16) -> bool {
        self.categories.iter().any(|c| c.kind == kind)
    }
    /// Index of the first SM of the given type.
    pub fn sm_of_kind(&self, kind: u8) -> Option<usize> {
        self.sync_managers.iter().position(|s| s.kind == kind)
    }
    pub fn category_list(&self) -> String {
        self.categories
            .iter()
            .map(|c| format!("{}({})/{}w", category_name(c.kind), c.kind, c.len_words))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// Decodes the strings category: a count byte, then length-prefixed strings.
pub fn decode_strings(data: &[u8]) -> Vec<String> {
    let mut out = Vec::new();
    let Some(&count) = data.first() else {
        return out;
    };
    let mut pos = 1usize;
    for _ in 0..count {
        let Some(&len) = data.get(pos) else { break };
        let start = pos + 1;
        let end = start + usize::from(len);
        let Some(bytes) = data.get(start..end) else {
            break;
        };
        out.push(String::from_utf8_lossy(bytes).into_owned());
        pos = end;
    }
    out
}

pub fn decode_sync_managers(data: &[u8]) -> Vec<SyncManagerEntry> {
    data.chunks_exact(8)
        .map(|c| SyncManagerEntry {
            start: u16::from_le_bytes([c[0], c[1]]),
            len: u16::from_le_bytes([c[2], c[3]]),
            control: c[4],
            enable: c[6],
            kind: c[7],
        })
        .collect()
}

async fn read_exact(
    sd: &SubDevice,
    md: &MainDevice<'_>,
    start_word: u16,
    buf: &mut [u8],
) -> Result<(), Error> {
    let n = sd.eeprom_read_raw(md, start_word, buf).await?;
    if n < buf.len() {
        return Err(Error::Internal);
    }
    Ok(())
}

/// Reads the header and walks the categories through ethercrab's EEPROM reader.
pub async fn read_sii(sd: &SubDevice, md: &MainDevice<'_>) -> Result<SiiInfo, String> {
    let mut info = SiiInfo {
        size_bytes: sd
            .eeprom_size(md)
            .await
            .map_err(|e| format!("EEPROM size (word 0x3E): {e}"))?,
        header: vec![0u8; 0x80],
        ..Default::default()
    };
    let mut header = vec![0u8; 0x80];
    read_exact(sd, md, 0, &mut header)
        .await
        .map_err(|e| format!("SII words 0x00..0x3F: {e}"))?;
    info.header = header;

    let mut w: u16 = 0x40;
    let limit_words = (info.size_bytes / 2).max(0x40) as u32;
    for _ in 0..128 {
        // The end marker is one word and may be the EEPROM's last (ETG.2010 §2.3); a
        // category header is two.
        if u32::from(w) + 1 > limit_words {
            return Err(format!(
                "category walk ran past the EEPROM size ({} bytes) at word {w:#06x} without an end marker",
                info.size_bytes
            ));
        }
        let mut kind_bytes = [0u8; 2];
        read_exact(sd, md, w, &mut kind_bytes)
            .await
            .map_err(|e| format!("category type at word {w:#06x}: {e}"))?;
        let kind = u16::from_le_bytes(kind_bytes);
        if kind == CAT_END {
            return Ok(info);
        }
        if u32::from(w) + 2 > limit_words {
            return Err(format!(
                "category {kind} at word {w:#06x} has no room for its length word in the EEPROM size ({} bytes)",
                info.size_bytes
            ));
        }
        let mut len_bytes = [0u8; 2];
        read_exact(sd, md, w + 1, &mut len_bytes)
            .await
            .map_err(|e| format!("category length at word {:#06x}: {e}", w + 1))?;
        let len_words = u16::from_le_bytes(len_bytes);
        let cat = Category {
            kind,
            start_word: w + 2,
            len_words,
        };
        info.categories.push(cat);
        if matches!(kind, CAT_STRINGS | CAT_GENERAL | CAT_FMMU | CAT_SYNCM) && len_words > 0 {
            let mut data = vec![0u8; usize::from(len_words) * 2];
            read_exact(sd, md, cat.start_word, &mut data)
                .await
                .map_err(|e| {
                    format!("category {kind} data at word {:#06x}: {e}", cat.start_word)
                })?;
            match kind {
                CAT_STRINGS => info.strings = decode_strings(&data),
                CAT_GENERAL => {
                    info.coe_details = data.get(5).copied();
                    let name_idx = data.get(3).copied().unwrap_or(0);
                    if name_idx > 0 {
                        info.general_name = info.strings.get(usize::from(name_idx) - 1).cloned();
                    }
                }
                CAT_FMMU => info.fmmu_usage = data.clone(),
                CAT_SYNCM => info.sync_managers = decode_sync_managers(&data),
                _ => {}
            }
        }
        w = w
            .checked_add(2 + len_words)
            .ok_or_else(|| "category walk overflowed the word address".to_string())?;
    }
    Err("more than 128 categories: no end marker found".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc8_is_poly_07_init_ff_unreflected() {
        // Check values over "123456789" and 0x00 for poly 0x07, init 0xFF, no reflection,
        // no final xor (the SII checksum parameters), worked out separately by hand/Python.
        assert_eq!(crc8(b"123456789"), 0xFB);
        assert_eq!(crc8(&[]), 0xFF);
        assert_eq!(crc8(&[0x00]), 0xF3);
        let bytes = [0x80, 0x0C, 0x00, 0x6E, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        assert_eq!(crc8(&bytes), crc8_reference(&bytes));
    }

    /// The CRC as a polynomial division, one message bit at a time, MSB first.
    fn crc8_reference(bytes: &[u8]) -> u8 {
        let mut reg: u16 = 0xFF;
        for &b in bytes {
            for i in (0..8).rev() {
                let bit = u16::from((b >> i) & 1);
                let top = (reg >> 7) & 1;
                reg = (reg << 1) & 0xFF;
                if top ^ bit == 1 {
                    reg ^= 0x07;
                }
            }
        }
        reg as u8
    }

    #[test]
    fn strings_category_decodes_count_and_lengths() {
        let data = [2u8, 3, b'a', b'b', b'c', 1, b'z', 0];
        assert_eq!(
            decode_strings(&data),
            vec!["abc".to_string(), "z".to_string()]
        );
        // truncated: stops instead of panicking
        assert_eq!(decode_strings(&[3u8, 5, b'a']), Vec::<String>::new());
    }

    #[test]
    fn sync_manager_entries_keep_the_type_byte() {
        let data = [
            0x00, 0x10, 0x80, 0x00, 0x26, 0x00, 0x01, 0x01, // SM0 mbx out
            0x80, 0x10, 0x80, 0x00, 0x22, 0x00, 0x01, 0x02, // SM1 mbx in
        ];
        let sms = decode_sync_managers(&data);
        assert_eq!(sms.len(), 2);
        assert_eq!(sms[0].start, 0x1000);
        assert_eq!(sms[0].len, 0x80);
        assert_eq!(sms[0].control, 0x26);
        assert_eq!(sms[1].kind, 2);
    }
}
