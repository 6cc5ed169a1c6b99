//! The SICK LMS 2xx telegram checksum: CRC-16 with generator 0x8005 over STX up to the
//! last data byte, as the LMS 2xx telegram listing computes it (two-byte running window).

/// The generator polynomial of the LMS 2xx CRC.
const GENERATOR: u16 = 0x8005;

/// The CRC of `bytes` (a telegram from STX up to and including its last data byte). On
/// the wire it follows as a little-endian `u16`.
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    let mut previous: u8 = 0;
    for &byte in bytes {
        crc = if crc & 0x8000 != 0 {
            ((crc & 0x7fff) << 1) ^ GENERATOR
        } else {
            crc << 1
        };
        crc ^= u16::from(byte) | (u16::from(previous) << 8);
        previous = byte;
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/ARCHITECTURE.md §5: whole frames whose last two bytes are the CRC of the rest.
    #[test]
    fn design_test_vectors() {
        let frames: [&[u8]; 3] = [
            &[0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08],
            &[0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08],
            &[0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08],
        ];
        for frame in frames {
            let (body, crc) = frame.split_at(frame.len() - 2);
            assert_eq!(
                crc16(body).to_le_bytes(),
                [crc[0], crc[1]],
                "frame {frame:02x?}"
            );
        }
    }

    #[test]
    fn one_flipped_bit_changes_the_crc() {
        let body = [0x02, 0x00, 0x02, 0x00, 0x20, 0x24];
        let good = crc16(&body);
        for i in 0..body.len() * 8 {
            let mut damaged = body;
            damaged[i / 8] ^= 1 << (i % 8);
            assert_ne!(crc16(&damaged), good, "bit {i}");
        }
    }
}
