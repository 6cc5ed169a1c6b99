//! The receiver side, for emulators: GGA and RMC sentences for a position, with the
//! NMEA checksum (XOR of the characters between `$` and `*`).

/// `ddmm.mmmm,H` for a signed angle (degrees) with `deg_digits` digits of degrees.
fn angle(value: f64, deg_digits: usize, positive: char, negative: char) -> String {
    let hemisphere = if value < 0.0 { negative } else { positive };
    let a = value.abs();
    let mut degrees = a.trunc();
    let mut minutes = (a - degrees) * 60.0;
    if (minutes * 1e4).round() >= 60.0e4 {
        degrees += 1.0;
        minutes = 0.0;
    }
    format!(
        "{:0w$}{:07.4},{hemisphere}",
        degrees as u32,
        minutes,
        w = deg_digits
    )
}

/// `$body*CS\r\n`.
fn with_checksum(body: &str) -> String {
    let cs = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("${body}*{cs:02X}\r\n")
}

/// `hhmmss.ss` for `utc_s` seconds after midnight UTC.
fn utc_time(utc_s: f64) -> String {
    let t = utc_s.rem_euclid(86_400.0);
    format!(
        "{:02}{:02}{:05.2}",
        (t / 3600.0) as u32,
        ((t % 3600.0) / 60.0) as u32,
        t % 60.0
    )
}

/// The GGA and RMC sentences of a receiver without a fix (fix quality 0, status `V`).
pub fn no_fix_sentences(utc_s: f64) -> String {
    let time = utc_time(utc_s);
    with_checksum(&format!("GPGGA,{time},,,,,0,00,,,M,,M,,"))
        + &with_checksum(&format!("GPRMC,{time},V,,,,,,,010124,,,N"))
}

/// A GGA and an RMC sentence for a GPS fix at `latitude`/`longitude` (degrees),
/// `altitude` (m), `hdop`, `utc_s` seconds after midnight UTC.
pub fn sentences(latitude: f64, longitude: f64, altitude: f64, hdop: f64, utc_s: f64) -> String {
    let time = utc_time(utc_s);
    let lat = angle(latitude, 2, 'N', 'S');
    let lon = angle(longitude, 3, 'E', 'W');
    let gga = with_checksum(&format!(
        "GPGGA,{time},{lat},{lon},1,08,{hdop:.1},{altitude:.1},M,0.0,M,,"
    ));
    let rmc = with_checksum(&format!("GPRMC,{time},A,{lat},{lon},0.0,0.0,010124,,,A"));
    gga + &rmc
}
