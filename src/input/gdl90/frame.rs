//! GDL 90 framing: flag bytes, byte stuffing and the frame check sequence,
//! as the public GDL 90 Data Interface Specification (Garmin
//! 560-1058-00 Rev A, 2007) defines them in §2.2:
//!
//! - a message is framed by flag bytes `0x7E`; back-to-back messages have
//!   two flags between them;
//! - inside a frame, `0x7E` and `0x7D` are sent as `0x7D` followed by the
//!   byte XOR `0x20`;
//! - the frame check sequence is CRC-CCITT (polynomial `0x1021`, initial
//!   value 0, no reflection, no final XOR) of the unstuffed message,
//!   appended least significant byte first (§2.2.3);
//! - a message ID with its most significant bit set is discarded (§2.2.2).
//!
//! Unstuffing writes into a fixed buffer: no datagram allocates.

use crate::input::update::Ignored;

/// The longest message taken, bytes with its ID and frame check sequence:
/// the uplink message (436) and its FCS, with room to spare.
pub const MAX_MESSAGE_BYTES: usize = 448;
const FLAG: u8 = 0x7E;
const ESCAPE: u8 = 0x7D;

/// The ICD's CRC table (§2.2.3 `crcInit`), made at compile time.
const CRC_TABLE: [u16; 256] = crc_table();

const fn crc_table() -> [u16; 256] {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = (i as u16) << 8;
        let mut bit = 0;
        while bit < 8 {
            crc = (crc << 1) ^ if crc & 0x8000 != 0 { 0x1021 } else { 0 };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
}

/// The frame check sequence of `message` (its ID and data), the ICD's
/// `crcCompute`.
pub fn crc(message: &[u8]) -> u16 {
    message
        .iter()
        .fold(0u16, |crc, &byte| CRC_TABLE[(crc >> 8) as usize] ^ (crc << 8) ^ byte as u16)
}

/// Calls `each` with every message of `datagram` (ID and data, FCS
/// checked and removed), in order. Returns the first problem met, after
/// handing over every good message: a datagram's bad frame does not hide
/// its good ones.
pub fn for_each_message(datagram: &[u8], mut each: impl FnMut(&[u8])) -> Result<(), Ignored> {
    if datagram.first() != Some(&FLAG) {
        return Err(Ignored::Header);
    }
    let mut problem = None;
    let mut buffer = [0u8; MAX_MESSAGE_BYTES];
    let mut rest = &datagram[1..];
    loop {
        let Some(end) = rest.iter().position(|&b| b == FLAG) else {
            // Bytes after the last flag: a frame that never closed.
            if !rest.is_empty() {
                problem.get_or_insert(Ignored::Framing);
            }
            break;
        };
        let (frame, after) = rest.split_at(end);
        rest = &after[1..];
        if frame.is_empty() {
            continue; // two flags in a row
        }
        match unstuff(frame, &mut buffer).and_then(|length| checked(&buffer[..length])) {
            Ok(message) => each(message),
            Err(reason) => {
                problem.get_or_insert(reason);
            }
        }
    }
    problem.map_or(Ok(()), Err)
}

/// Removes the byte stuffing of `frame` into `buffer`; the unstuffed length.
fn unstuff(frame: &[u8], buffer: &mut [u8; MAX_MESSAGE_BYTES]) -> Result<usize, Ignored> {
    let mut length = 0;
    let mut bytes = frame.iter();
    while let Some(&byte) = bytes.next() {
        let byte = if byte == ESCAPE {
            match bytes.next() {
                Some(&next) => next ^ 0x20,
                None => return Err(Ignored::Framing),
            }
        } else {
            byte
        };
        *buffer.get_mut(length).ok_or(Ignored::Framing)? = byte;
        length += 1;
    }
    Ok(length)
}

/// The message of an unstuffed frame whose FCS matches.
fn checked(frame: &[u8]) -> Result<&[u8], Ignored> {
    if frame.len() < 3 {
        return Err(Ignored::Length);
    }
    let (message, fcs) = frame.split_at(frame.len() - 2);
    if crc(message) != u16::from_le_bytes([fcs[0], fcs[1]]) {
        return Err(Ignored::Crc);
    }
    if message[0] & 0x80 != 0 {
        return Err(Ignored::Header);
    }
    Ok(message)
}

/// `message` (ID and data) framed for sending: FCS appended, stuffed,
/// between flags.
pub fn frame(message: &[u8]) -> Vec<u8> {
    let fcs = crc(message).to_le_bytes();
    let mut framed = vec![FLAG];
    for &byte in message.iter().chain(&fcs) {
        if byte == FLAG || byte == ESCAPE {
            framed.extend_from_slice(&[ESCAPE, byte ^ 0x20]);
        } else {
            framed.push(byte);
        }
    }
    framed.push(FLAG);
    framed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// §2.2.4: a heartbeat with its flags and CRC.
    const ICD_HEARTBEAT: [u8; 11] =
        [0x7E, 0x00, 0x81, 0x41, 0xDB, 0xD0, 0x08, 0x02, 0xB3, 0x8B, 0x7E];

    #[test]
    fn the_icd_example_heartbeat_checks() {
        assert_eq!(crc(&ICD_HEARTBEAT[1..8]), 0x8BB3);
        assert_eq!(frame(&ICD_HEARTBEAT[1..8]), ICD_HEARTBEAT);
        let mut seen = Vec::new();
        for_each_message(&ICD_HEARTBEAT, |m| seen.push(m.to_vec())).expect("valid");
        assert_eq!(seen, vec![ICD_HEARTBEAT[1..8].to_vec()]);
    }

    #[test]
    fn stuffed_bytes_and_back_to_back_frames_come_through() {
        let a = [0x02, 0x7E, 0x7D, 0x11];
        let b = [0x03, 0x7D];
        let mut datagram = frame(&a);
        datagram.extend(frame(&b));
        assert!(datagram.windows(2).any(|w| w == [0x7D, 0x5E]), "0x7E is stuffed");
        let mut seen = Vec::new();
        for_each_message(&datagram, |m| seen.push(m.to_vec())).expect("valid");
        assert_eq!(seen, vec![a.to_vec(), b.to_vec()]);
    }

    #[test]
    fn broken_frames_are_refused_by_reason() {
        let good = frame(&[0x0B, 0x00, 0xC8, 0x00, 0x0A]);
        let mut flipped = good.clone();
        flipped[3] ^= 0x01;
        let check = |d: &[u8]| for_each_message(d, |_| {});
        assert_eq!(check(&flipped), Err(Ignored::Crc));
        assert_eq!(check(&good[1..]), Err(Ignored::Header));
        assert_eq!(check(&good[..good.len() - 1]), Err(Ignored::Framing));
        assert_eq!(check(&[0x7E, 0x0B, 0x7D, 0x7E]), Err(Ignored::Framing));
        assert_eq!(check(&[0x7E, 0x0B, 0x00, 0x7E]), Err(Ignored::Length));
        assert_eq!(check(&frame(&[0x8B, 1, 2])), Err(Ignored::Header));
        let long = vec![0x07; MAX_MESSAGE_BYTES + 1];
        assert_eq!(check(&frame(&long)), Err(Ignored::Framing));
    }
}
