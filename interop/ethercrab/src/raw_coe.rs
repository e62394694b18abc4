//! SDO transfers that ethercrab 0.7.1 does not offer, built on its public register commands.
//!
//! ethercrab's `sdo_write` only does expedited downloads (at most 4 bytes; longer values
//! return `Error::Internal`), so normal and segmented downloads (ETG.1000.6 §5.6.2.1–5.6.2.3)
//! are written here by hand: the request goes into the receive mailbox with FPWR, the
//! response comes from the send mailbox with FPRD once its SM status says "full", exactly as
//! ethercrab's own mailbox code does. An upload is implemented too, so the transfer type the
//! slave chose (expedited / normal / segmented) can be reported.
//!
//! Mailbox counter: a slave treats a request whose counter equals the previous one as a
//! repeat (ETG.1000.4 §5.6 mailbox header "Cnt"; ETG.1000.6 §5.6). ethercrab keeps its own
//! counter per SubDevice (next value 1..7), so every counter used here differs from the one
//! the slave saw last and from the one ethercrab will use next; ethercrab's next counter is
//! read from `SubDevice`'s Debug output (the field is not public).

use ethercrab::{Command, MainDevice, SubDevice};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Mailbox header (6) + CoE header (2) + SDO command/index/subindex (4) + size/data (4).
const SDO_HEADER: usize = 16;
const MAILBOX_TYPE_COE: u8 = 0x03;
const COE_SDO_REQUEST: u16 = 2;
const COE_SDO_RESPONSE: u16 = 3;
const COE_SDO_INFO: u16 = 8;
const RESPONSE_TIMEOUT: Duration = Duration::from_secs(1);

/// (station, last counter sent from here, ethercrab's next counter at that moment), shared by
/// every `RawMailbox` so a new one does not repeat the counter an earlier one left behind.
static LAST_SENT: Mutex<Vec<(u16, u8, u8)>> = Mutex::new(Vec::new());

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UploadKind {
    Expedited,
    Normal,
    Segmented { segments: usize },
}

#[derive(Debug, Clone, Copy)]
pub struct MailboxArea {
    pub sm: u8,
    pub start: u16,
    pub len: u16,
}

pub struct RawMailbox<'a> {
    md: &'a MainDevice<'a>,
    station: u16,
    rx: MailboxArea,
    tx: MailboxArea,
    last_sent: u8,
}

/// ethercrab's next mailbox counter for this SubDevice, read from its Debug output.
pub fn ethercrab_next_counter(sd: &SubDevice) -> Option<u8> {
    let text = format!("{sd:?}");
    let at = text.find("mailbox_counter: ")? + "mailbox_counter: ".len();
    let digits: String = text[at..]
        .chars()
        .take_while(|c| c.is_ascii_digit())
        .collect();
    digits.parse().ok()
}

fn prev_counter(c: u8) -> u8 {
    if c <= 1 { 7 } else { c - 1 }
}

fn next_counter(c: u8) -> u8 {
    if c >= 7 { 1 } else { c + 1 }
}

/// Picks a counter that is neither the last one the slave saw (ours or ethercrab's) nor the
/// one ethercrab will send next.
pub fn pick_counter(last_sent: u8, ethercrab_next: u8) -> u8 {
    let mut c = next_counter(last_sent);
    while c == ethercrab_next || c == prev_counter(ethercrab_next) || c == last_sent {
        c = next_counter(c);
    }
    c
}

fn abort_text(code: u32) -> String {
    let what = match code {
        0x0503_0000 => "toggle bit not changed",
        0x0504_0001 => "command specifier not valid",
        0x0601_0000 => "unsupported access",
        0x0601_0001 => "write-only object read",
        0x0601_0002 => "read-only object written",
        0x0602_0000 => "object does not exist",
        0x0607_0010 => "data type / length mismatch",
        0x0607_0012 => "length too high",
        0x0607_0013 => "length too low",
        0x0609_0011 => "subindex does not exist",
        0x0800_0000 => "general error",
        0x0800_0022 => "not in this device state",
        _ => "see ETG.1000.6 Table 41",
    };
    format!("SDO abort {code:#010x} ({what})")
}

impl<'a> RawMailbox<'a> {
    /// Reads the mailbox SM registers the master (ethercrab) configured; `rx_sm` is the
    /// master -> slave mailbox SM (SII type 1), `tx_sm` the slave -> master one (type 2).
    pub async fn open(
        md: &'a MainDevice<'a>,
        station: u16,
        rx_sm: u8,
        tx_sm: u8,
    ) -> Result<RawMailbox<'a>, String> {
        let read_sm = |sm: u8| async move {
            let reg = 0x0800 + 8 * u16::from(sm);
            let raw = Command::fprd(station, reg)
                .receive::<[u8; 8]>(md)
                .await
                .map_err(|e| format!("FPRD SM{sm} {reg:#06x}: {e}"))?;
            Ok::<_, String>(MailboxArea {
                sm,
                start: u16::from_le_bytes([raw[0], raw[1]]),
                len: u16::from_le_bytes([raw[2], raw[3]]),
            })
        };
        let rx = read_sm(rx_sm).await?;
        let tx = read_sm(tx_sm).await?;
        if usize::from(rx.len) < SDO_HEADER || usize::from(tx.len) < SDO_HEADER {
            return Err(format!(
                "mailbox SMs too small for SDO: SM{} {} bytes, SM{} {} bytes",
                rx.sm, rx.len, tx.sm, tx.len
            ));
        }
        Ok(RawMailbox {
            md,
            station,
            rx,
            tx,
            last_sent: 0,
        })
    }

    /// The counter this program last sent to `station`, if ethercrab sent nothing since (then
    /// the slave still holds it as its "previous" counter).
    fn remembered_counter(station: u16, ethercrab_next: u8) -> u8 {
        let sent = LAST_SENT.lock().unwrap_or_else(|e| e.into_inner());
        sent.iter()
            .find(|(st, _, next)| *st == station && *next == ethercrab_next)
            .map(|(_, c, _)| *c)
            .unwrap_or(0)
    }

    fn remember_counter(station: u16, counter: u8, ethercrab_next: u8) {
        let mut sent = LAST_SENT.lock().unwrap_or_else(|e| e.into_inner());
        sent.retain(|(st, _, _)| *st != station);
        sent.push((station, counter, ethercrab_next));
    }

    async fn sm_status(&self, sm: u8) -> Result<u8, String> {
        let reg = 0x0805 + 8 * u16::from(sm);
        Command::fprd(self.station, reg)
            .receive::<u8>(self.md)
            .await
            .map_err(|e| format!("FPRD SM{sm} status {reg:#06x}: {e}"))
    }

    async fn read_tx(&self) -> Result<Vec<u8>, String> {
        let pdu = Command::fprd(self.station, self.tx.start)
            .receive_slice(self.md, self.tx.len)
            .await
            .map_err(|e| format!("FPRD send mailbox {:#06x}: {e}", self.tx.start))?;
        Ok(pdu.to_vec())
    }

    /// Sends one CoE request (CoE header onwards) and returns the response's mailbox data
    /// (CoE header onwards, `length` bytes from the mailbox header).
    async fn exchange(&mut self, sd: &SubDevice, coe: &[u8]) -> Result<Vec<u8>, String> {
        let ethercrab_next = ethercrab_next_counter(sd).ok_or_else(|| {
            "cannot read ethercrab's mailbox counter from SubDevice's Debug output".to_string()
        })?;
        if self.last_sent == 0 {
            self.last_sent = Self::remembered_counter(self.station, ethercrab_next);
        }
        let counter = pick_counter(self.last_sent, ethercrab_next);

        // A stale response left in the send mailbox would be taken for ours.
        if self.sm_status(self.tx.sm).await? & 0x08 != 0 {
            let stale = self.read_tx().await?;
            log::warn!(
                "{:#06x}: send mailbox was full before our request; discarded {:02x?}",
                self.station,
                &stale[..stale.len().min(16)]
            );
        }
        let deadline = Instant::now() + RESPONSE_TIMEOUT;
        while self.sm_status(self.rx.sm).await? & 0x08 != 0 {
            if Instant::now() > deadline {
                return Err(format!(
                    "receive mailbox SM{} stayed full for 1 s",
                    self.rx.sm
                ));
            }
            std::thread::sleep(Duration::from_millis(1));
        }

        let mut frame = vec![0u8; usize::from(self.rx.len)];
        let len = u16::try_from(coe.len()).map_err(|_| "request too long".to_string())?;
        if coe.len() + 6 > frame.len() {
            return Err(format!(
                "request of {} bytes does not fit the {}-byte mailbox",
                coe.len() + 6,
                frame.len()
            ));
        }
        frame[0..2].copy_from_slice(&len.to_le_bytes());
        // address 0 (master), channel 0, priority 0
        frame[5] = MAILBOX_TYPE_COE | (counter << 4);
        frame[6..6 + coe.len()].copy_from_slice(coe);
        // The whole SM area is written so the last byte hands the buffer to the slave.
        Command::fpwr(self.station, self.rx.start)
            .send(self.md, &frame[..])
            .await
            .map_err(|e| {
                format!(
                    "FPWR receive mailbox {:#06x} ({} bytes, counter {counter}): {e}",
                    self.rx.start,
                    frame.len()
                )
            })?;
        self.last_sent = counter;
        Self::remember_counter(self.station, counter, ethercrab_next);

        let deadline = Instant::now() + RESPONSE_TIMEOUT;
        while self.sm_status(self.tx.sm).await? & 0x08 == 0 {
            if Instant::now() > deadline {
                return Err(format!(
                    "no response in the send mailbox SM{} within 1 s (request counter {counter}, {:02x?})",
                    self.tx.sm,
                    &coe[..coe.len().min(16)]
                ));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let resp = self.read_tx().await?;
        let rlen = usize::from(u16::from_le_bytes([resp[0], resp[1]]));
        let rtype = resp[5] & 0x0F;
        if rtype != MAILBOX_TYPE_COE {
            return Err(format!(
                "response mailbox type {rtype} (expected 3 = CoE): {:02x?}",
                &resp[..resp.len().min(16)]
            ));
        }
        if rlen < 2 || 6 + rlen > resp.len() {
            return Err(format!(
                "response mailbox length {rlen} does not fit the {}-byte send mailbox",
                resp.len()
            ));
        }
        Ok(resp[6..6 + rlen].to_vec())
    }

    /// Checks the CoE/SDO response header; returns the SDO command byte.
    fn sdo_response(body: &[u8], index: u16, sub: u8, what: &str) -> Result<u8, String> {
        if body.len() < 10 {
            return Err(format!(
                "{what}: SDO response of {} bytes (<10): {body:02x?}",
                body.len()
            ));
        }
        let service = u16::from_le_bytes([body[0], body[1]]) >> 12;
        let cmd = body[2];
        if service == COE_SDO_REQUEST && cmd == 0x80 {
            let code = u32::from_le_bytes([body[6], body[7], body[8], body[9]]);
            return Err(format!("{what}: {}", abort_text(code)));
        }
        if service != COE_SDO_RESPONSE {
            return Err(format!(
                "{what}: CoE service {service} (expected 3 = SDO response): {:02x?}",
                &body[..body.len().min(16)]
            ));
        }
        let ridx = u16::from_le_bytes([body[3], body[4]]);
        if (cmd >> 5) != 0 && (cmd >> 5) != 1 && (ridx != index || body[5] != sub) {
            return Err(format!(
                "{what}: response is for {ridx:#06x}:{:02x}, not {index:#06x}:{sub:02x} (a repeated reply?)",
                body[5]
            ));
        }
        Ok(cmd)
    }

    /// Normal or segmented download (ETG.1000.6 §5.6.2.2/5.6.2.3). `first_chunk` limits the
    /// data sent in the initiate request and `segment_max` the data per segment; with the
    /// defaults (None) the data goes in one request when it fits, the way SOEM does it.
    pub async fn download(
        &mut self,
        sd: &SubDevice,
        index: u16,
        sub: u8,
        data: &[u8],
        first_chunk: Option<usize>,
        segment_max: Option<usize>,
    ) -> Result<usize, String> {
        let capacity = usize::from(self.rx.len) - SDO_HEADER;
        let first = data
            .len()
            .min(first_chunk.unwrap_or(capacity))
            .min(capacity);
        let size = u32::try_from(data.len()).map_err(|_| "data too long".to_string())?;
        let mut req = Vec::with_capacity(10 + first);
        req.extend_from_slice(&(COE_SDO_REQUEST << 12).to_le_bytes());
        // ccs = 1 (initiate download), size indicated, not expedited
        req.push(0x21);
        req.extend_from_slice(&index.to_le_bytes());
        req.push(sub);
        req.extend_from_slice(&size.to_le_bytes());
        req.extend_from_slice(&data[..first]);
        let what = format!("download {index:#06x}:{sub:02x} initiate");
        let body = self.exchange(sd, &req).await?;
        let cmd = Self::sdo_response(&body, index, sub, &what)?;
        if cmd >> 5 != 3 {
            return Err(format!(
                "{what}: response command {cmd:#04x} (expected scs 3, 0x60)"
            ));
        }

        // Segment data: at most mailbox - 6 (mailbox header) - 3 (CoE header + command).
        let seg_capacity = usize::from(self.rx.len) - 9;
        let seg_max = segment_max.unwrap_or(seg_capacity).clamp(1, seg_capacity);
        let mut offset = first;
        let mut toggle = 0u8;
        let mut segments = 0usize;
        while offset < data.len() {
            let n = (data.len() - offset).min(seg_max);
            let last = offset + n == data.len();
            let unused = if n < 7 { 7 - n } else { 0 } as u8;
            let mut req = Vec::with_capacity(3 + n.max(7));
            req.extend_from_slice(&(COE_SDO_REQUEST << 12).to_le_bytes());
            // ccs = 0 (download segment), toggle, unused bytes, last segment
            req.push((toggle << 4) | (unused << 1) | u8::from(last));
            req.extend_from_slice(&data[offset..offset + n]);
            req.resize(3 + n.max(7), 0);
            let what = format!("download {index:#06x}:{sub:02x} segment {segments}");
            let body = self.exchange(sd, &req).await?;
            let cmd = Self::sdo_response(&body, index, sub, &what)?;
            if cmd >> 5 != 1 || (cmd >> 4) & 1 != toggle {
                return Err(format!(
                    "{what}: response command {cmd:#04x} (expected scs 1 with toggle {toggle})"
                ));
            }
            offset += n;
            toggle ^= 1;
            segments += 1;
        }
        Ok(segments)
    }

    /// SDO Information "Get OD List" (ETG.1000.6 §5.6.3.3): one request, then as many
    /// fragments as the slave announces. Returns the indices carried by each fragment (the
    /// list type word, first in the first fragment only, is checked and left out).
    pub async fn od_list(
        &mut self,
        sd: &SubDevice,
        list_type: u16,
    ) -> Result<Vec<Vec<u16>>, String> {
        let mut req = Vec::with_capacity(8);
        req.extend_from_slice(&(COE_SDO_INFO << 12).to_le_bytes());
        req.extend_from_slice(&[0x01, 0x00, 0x00, 0x00]); // Get OD List request, no fragments
        req.extend_from_slice(&list_type.to_le_bytes());
        let mut body = self.exchange(sd, &req).await?;
        let mut fragments = Vec::new();
        let mut expected_left: Option<u16> = None;
        loop {
            if body.len() < 6 {
                return Err(format!(
                    "SDO info response of {} bytes: {body:02x?}",
                    body.len()
                ));
            }
            let service = u16::from_le_bytes([body[0], body[1]]) >> 12;
            let opcode = body[2] & 0x7F;
            let incomplete = body[2] & 0x80 != 0;
            let left = u16::from_le_bytes([body[4], body[5]]);
            if service != COE_SDO_INFO {
                return Err(format!(
                    "CoE service {service} in an SDO info exchange: {:02x?}",
                    &body[..body.len().min(16)]
                ));
            }
            if opcode == 0x07 {
                let code = body
                    .get(6..10)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]));
                return Err(format!(
                    "SDO info error request: {}",
                    code.map(abort_text).unwrap_or_default()
                ));
            }
            if opcode != 0x02 {
                return Err(format!(
                    "SDO info opcode {opcode:#04x} (expected 0x02 Get OD List response)"
                ));
            }
            if let Some(want) = expected_left {
                if left != want {
                    return Err(format!("fragments left {left}, expected {want}"));
                }
            }
            let mut data = &body[6..];
            if fragments.is_empty() {
                if data.len() < 2 || u16::from_le_bytes([data[0], data[1]]) != list_type {
                    return Err(format!(
                        "first fragment does not start with list type {list_type}: {:02x?}",
                        &data[..data.len().min(8)]
                    ));
                }
                data = &data[2..];
            }
            if data.len() % 2 != 0 {
                return Err(format!(
                    "fragment {} carries an odd {} bytes",
                    fragments.len(),
                    data.len()
                ));
            }
            fragments.push(
                data.chunks_exact(2)
                    .map(|c| u16::from_le_bytes([c[0], c[1]]))
                    .collect(),
            );
            if !incomplete {
                if left != 0 {
                    return Err(format!("last fragment says {left} fragments left"));
                }
                return Ok(fragments);
            }
            if left == 0 {
                return Err("fragment marked incomplete with 0 fragments left".to_string());
            }
            expected_left = Some(left - 1);
            body = self.receive_more().await?;
        }
    }

    /// Waits for the next unsolicited mailbox from the slave (a further fragment).
    async fn receive_more(&mut self) -> Result<Vec<u8>, String> {
        let deadline = Instant::now() + RESPONSE_TIMEOUT;
        while self.sm_status(self.tx.sm).await? & 0x08 == 0 {
            if Instant::now() > deadline {
                return Err("next fragment did not arrive within 1 s".to_string());
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let resp = self.read_tx().await?;
        let rlen = usize::from(u16::from_le_bytes([resp[0], resp[1]]));
        if resp[5] & 0x0F != MAILBOX_TYPE_COE || rlen < 2 || 6 + rlen > resp.len() {
            return Err(format!(
                "unexpected mailbox {:02x?}",
                &resp[..resp.len().min(16)]
            ));
        }
        Ok(resp[6..6 + rlen].to_vec())
    }

    /// Upload; returns the data and the transfer type the slave chose.
    pub async fn upload(
        &mut self,
        sd: &SubDevice,
        index: u16,
        sub: u8,
    ) -> Result<(Vec<u8>, UploadKind), String> {
        let mut req = Vec::with_capacity(10);
        req.extend_from_slice(&(COE_SDO_REQUEST << 12).to_le_bytes());
        req.push(0x40); // ccs = 2 (initiate upload)
        req.extend_from_slice(&index.to_le_bytes());
        req.push(sub);
        req.extend_from_slice(&[0; 4]);
        let what = format!("upload {index:#06x}:{sub:02x}");
        let body = self.exchange(sd, &req).await?;
        let cmd = Self::sdo_response(&body, index, sub, &what)?;
        if cmd >> 5 != 2 {
            return Err(format!(
                "{what}: response command {cmd:#04x} (expected scs 2)"
            ));
        }
        if cmd & 0x02 != 0 {
            let n = if cmd & 0x01 != 0 {
                4 - usize::from((cmd >> 2) & 0x03)
            } else {
                4
            };
            return Ok((body[6..6 + n].to_vec(), UploadKind::Expedited));
        }
        let complete = u32::from_le_bytes([body[6], body[7], body[8], body[9]]) as usize;
        let mut data = body[10..].to_vec();
        if data.len() >= complete {
            data.truncate(complete);
            return Ok((data, UploadKind::Normal));
        }
        let mut toggle = 0u8;
        let mut segments = 0usize;
        loop {
            let mut req = Vec::with_capacity(10);
            req.extend_from_slice(&(COE_SDO_REQUEST << 12).to_le_bytes());
            req.push(0x60 | (toggle << 4)); // ccs = 3 (upload segment)
            req.extend_from_slice(&[0; 7]);
            let what = format!("upload {index:#06x}:{sub:02x} segment {segments}");
            let body = self.exchange(sd, &req).await?;
            if body.len() < 10 {
                return Err(format!("{what}: {} bytes (<10): {body:02x?}", body.len()));
            }
            let service = u16::from_le_bytes([body[0], body[1]]) >> 12;
            let cmd = body[2];
            if service == COE_SDO_REQUEST && cmd == 0x80 {
                let code = u32::from_le_bytes([body[6], body[7], body[8], body[9]]);
                return Err(format!("{what}: {}", abort_text(code)));
            }
            if service != COE_SDO_RESPONSE || cmd >> 5 != 0 || (cmd >> 4) & 1 != toggle {
                return Err(format!(
                    "{what}: response service {service} command {cmd:#04x} (expected service 3, scs 0, toggle {toggle})"
                ));
            }
            let mut n = body.len() - 3;
            if n == 7 {
                n -= usize::from((cmd >> 1) & 0x07);
            }
            data.extend_from_slice(&body[3..3 + n]);
            segments += 1;
            toggle ^= 1;
            if cmd & 0x01 != 0 {
                break;
            }
            if data.len() > complete {
                return Err(format!(
                    "{what}: {} bytes received, more than the announced {complete}",
                    data.len()
                ));
            }
        }
        if data.len() != complete {
            return Err(format!(
                "{what}: {} bytes received, {complete} announced",
                data.len()
            ));
        }
        Ok((data, UploadKind::Segmented { segments }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_avoid_the_slaves_last_and_ethercrabs_next() {
        for last in 0..=7u8 {
            for next in 1..=7u8 {
                let c = pick_counter(last, next);
                assert!((1..=7).contains(&c));
                assert_ne!(c, last);
                assert_ne!(c, next);
                assert_ne!(c, prev_counter(next));
            }
        }
        assert_eq!(prev_counter(1), 7);
        assert_eq!(next_counter(7), 1);
    }

    #[test]
    fn abort_text_names_the_code() {
        assert!(abort_text(0x0602_0000).contains("does not exist"));
        assert!(abort_text(0x1234_5678).contains("0x12345678"));
    }
}
