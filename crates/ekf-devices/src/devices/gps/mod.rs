//! The GPS (the paper's HOLUX UB-93): NMEA 0183 lines parsed with the `nmea` crate, GGA
//! and RMC turned into `sensor_msgs/NavSatFix`; and the receiver side (sentences with
//! checksums) for emulation.

pub mod device;

use ekf_ros::ros2::builtin_interfaces::Time;
use ekf_ros::ros2::sensor_msgs::{NavSatFix, NavSatStatus};
use ekf_ros::ros2::std_msgs::Header;
use nmea::sentences::FixType;
use nmea::ParseResult;

/// Longest NMEA sentence accepted (the standard's 82 characters, with some slack for
/// receivers that exceed it).
pub const MAX_LINE: usize = 120;
/// User equivalent range error of a consumer receiver (m, 1σ): the position's standard
/// deviation is HDOP times this.
pub const UERE_M: f64 = 4.0;

/// A position fix from one sentence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fix {
    /// Latitude (degrees, north positive).
    pub latitude: f64,
    /// Longitude (degrees, east positive).
    pub longitude: f64,
    /// Altitude above mean sea level (m), when the sentence has one (GGA).
    pub altitude: Option<f64>,
    /// Horizontal dilution of precision, when given.
    pub hdop: Option<f64>,
    /// Whether the receiver used differential corrections.
    pub differential: bool,
}

impl Fix {
    /// The fix as `sensor_msgs/NavSatFix` at `stamp_ns` in `frame_id`; altitude NaN when
    /// unknown; the covariance approximated from HDOP (unknown without it).
    pub fn to_nav_sat_fix(&self, stamp_ns: u64, frame_id: &str) -> NavSatFix {
        let mut covariance = [0.0; 9];
        let covariance_type = match self.hdop {
            Some(hdop) => {
                let horizontal = (hdop * UERE_M).powi(2);
                covariance[0] = horizontal;
                covariance[4] = horizontal;
                covariance[8] = 4.0 * horizontal;
                NavSatFix::COVARIANCE_TYPE_APPROXIMATED
            }
            None => NavSatFix::COVARIANCE_TYPE_UNKNOWN,
        };
        NavSatFix {
            header: Header {
                stamp: Time::from_nanos(stamp_ns).unwrap_or_default(),
                frame_id: frame_id.into(),
            },
            status: NavSatStatus {
                status: if self.differential {
                    NavSatStatus::STATUS_SBAS_FIX
                } else {
                    NavSatStatus::STATUS_FIX
                },
                service: NavSatStatus::SERVICE_GPS,
            },
            latitude: self.latitude,
            longitude: self.longitude,
            altitude: self.altitude.unwrap_or(f64::NAN),
            position_covariance: covariance,
            position_covariance_type: covariance_type,
        }
    }
}

/// What one line was.
#[derive(Debug, Clone, PartialEq)]
pub enum Sentence {
    /// A GGA or RMC sentence with a valid position.
    Fix(Fix),
    /// A GGA or RMC sentence saying the receiver has no fix.
    NoFix,
    /// Another (valid) sentence, ignored.
    Other,
    /// A line that is not a valid sentence (checksum, syntax), with the reason.
    Invalid(String),
}

/// Counts of what the reader has seen.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct NmeaCounters {
    /// Fixes delivered.
    pub fixes: u64,
    /// GGA/RMC sentences without a fix.
    pub no_fix: u64,
    /// Lines that were not valid sentences (bad checksum, syntax, too long).
    pub invalid: u64,
}

/// Splits a byte stream into NMEA lines and parses them.
#[derive(Debug, Default)]
pub struct NmeaReader {
    line: Vec<u8>,
    overlong: bool,
    /// Counts so far.
    pub counters: NmeaCounters,
    /// Whether GGA sentences arrive: RMC fixes are then not used (GGA has altitude).
    seen_gga: bool,
    /// The UTC time field (`hhmmss.ss`) of the last fix delivered: one fix per epoch,
    /// also when an RMC comes before the first GGA.
    last_epoch: Option<String>,
}

impl NmeaReader {
    /// A reader at the start of a stream.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds bytes; returns the sentences completed by them.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<Sentence> {
        let mut out = Vec::new();
        for &b in bytes {
            if b == b'\n' {
                let line = std::mem::take(&mut self.line);
                if !self.overlong && line.iter().all(|c| *c == b'\r') {
                    // An empty line is no sentence: it does not show a receiver is there.
                    continue;
                }
                let sentence = if std::mem::take(&mut self.overlong) {
                    Sentence::Invalid(format!("line longer than {MAX_LINE} bytes"))
                } else {
                    self.parse_line(&line)
                };
                match &sentence {
                    Sentence::Fix(_) => self.counters.fixes += 1,
                    Sentence::NoFix => self.counters.no_fix += 1,
                    Sentence::Invalid(_) => self.counters.invalid += 1,
                    Sentence::Other => {}
                }
                out.push(sentence);
            } else if self.line.len() < MAX_LINE {
                self.line.push(b);
            } else {
                self.overlong = true;
            }
        }
        out
    }

    fn parse_line(&mut self, line: &[u8]) -> Sentence {
        let Ok(text) = std::str::from_utf8(line) else {
            return Sentence::Invalid("not ASCII".into());
        };
        let text = text.trim_end_matches('\r');
        let sentence = self.parse_sentence(text);
        let Sentence::Fix(fix) = &sentence else {
            return sentence;
        };
        // The sentence's checksum can be right and its numbers still off the globe (a
        // receiver's bug, a corrupted field with a recomputed checksum).
        if !(fix.latitude.abs() <= 90.0 && fix.longitude.abs() <= 180.0) {
            return Sentence::Invalid(format!(
                "{text:?}: fix off the globe: latitude {}° (expected within ±90), longitude \
                 {}° (expected within ±180)",
                fix.latitude, fix.longitude
            ));
        }
        // The time field: the second field of GGA and RMC.
        let epoch = text.split(',').nth(1).unwrap_or_default();
        if !epoch.is_empty() && self.last_epoch.as_deref() == Some(epoch) {
            return Sentence::Other;
        }
        self.last_epoch = Some(epoch.to_owned());
        sentence
    }

    fn parse_sentence(&mut self, text: &str) -> Sentence {
        match nmea::parse_str(text) {
            Ok(ParseResult::GGA(gga)) => {
                self.seen_gga = true;
                match (gga.fix_type, gga.latitude, gga.longitude) {
                    (Some(t), Some(latitude), Some(longitude)) if t.is_valid() => {
                        Sentence::Fix(Fix {
                            latitude,
                            longitude,
                            altitude: gga.altitude.map(f64::from),
                            hdop: gga.hdop.map(f64::from),
                            differential: t == FixType::DGps,
                        })
                    }
                    _ => Sentence::NoFix,
                }
            }
            Ok(ParseResult::RMC(rmc)) => match (rmc.status_of_fix, rmc.lat, rmc.lon) {
                (nmea::sentences::rmc::RmcStatusOfFix::Invalid, _, _) => Sentence::NoFix,
                _ if self.seen_gga => Sentence::Other,
                (status, Some(latitude), Some(longitude)) => Sentence::Fix(Fix {
                    latitude,
                    longitude,
                    altitude: None,
                    hdop: None,
                    differential: status == nmea::sentences::rmc::RmcStatusOfFix::Differential,
                }),
                _ => Sentence::NoFix,
            },
            Ok(_) => Sentence::Other,
            Err(e) => Sentence::Invalid(format!("{text:?}: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::device::{no_fix_sentences, sentences};
    use super::*;

    #[test]
    fn gga_and_rmc_become_fixes() {
        let mut r = NmeaReader::new();
        let text = sentences(21.0380, 105.7827, 12.5, 1.2, 3723.5);
        let found = r.push(text.as_bytes());
        let Sentence::Fix(f) = found[0] else {
            panic!("{found:?}");
        };
        assert!((f.latitude - 21.0380).abs() < 1e-6 && (f.longitude - 105.7827).abs() < 1e-6);
        assert_eq!(f.altitude, Some(12.5));
        // RMC after GGA adds nothing.
        assert_eq!(found[1], Sentence::Other);
        let msg = f.to_nav_sat_fix(5_000_000_000, "gps");
        assert_eq!(msg.header.stamp.sec, 5);
        assert!((msg.position_covariance[0] - (1.2f64 * 4.0).powi(2)).abs() < 1e-4);
        assert_eq!(r.counters.fixes, 1);
    }

    #[test]
    fn bad_checksums_and_no_fix_are_counted() {
        let mut r = NmeaReader::new();
        let good = sentences(-33.5, -70.25, 500.0, 0.9, 0.0);
        let mut bad = good.clone().into_bytes();
        bad[20] ^= 0x01;
        let found = r.push(&bad);
        assert!(matches!(found[0], Sentence::Invalid(_)), "{found:?}");
        r.push(b"$GPGGA,123519,,,,,0,00,,,M,,M,,*6B\r\n");
        r.push(&[b'x'; 300]);
        r.push(b"\n");
        assert_eq!(r.counters.no_fix, 1);
        assert_eq!(r.counters.invalid, 2);
        // (The RMC after the damaged GGA gave that epoch's fix: the next epoch's GGA.)
        let next = sentences(-33.5, -70.25, 500.0, 0.9, 1.0);
        let Sentence::Fix(f) = r.push(next.as_bytes())[0] else {
            panic!("a good GGA after the noise must parse");
        };
        assert!((f.latitude + 33.5).abs() < 1e-6 && (f.longitude + 70.25).abs() < 1e-6);
    }

    #[test]
    fn one_fix_per_epoch_and_empty_lines_are_no_sentences() {
        let mut r = NmeaReader::new();
        // The stream starts with an epoch's RMC; its GGA follows.
        let epoch = sentences(21.0380, 105.7827, 12.5, 1.2, 3723.5);
        let (gga, rmc) = epoch.split_at(epoch.find("$GPRMC").unwrap());
        let mut found = r.push(rmc.as_bytes());
        found.extend(r.push(gga.as_bytes()));
        let fixes = found
            .iter()
            .filter(|s| matches!(s, Sentence::Fix(_)))
            .count();
        assert_eq!(fixes, 1, "{found:?}");
        // The next epochs: one fix each, the GGA's.
        let next = sentences(21.0381, 105.7827, 12.5, 1.2, 3724.5);
        let found = r.push(next.as_bytes());
        assert!(matches!(found[0], Sentence::Fix(f) if f.altitude == Some(12.5)));
        assert_eq!(found[1], Sentence::Other);
        assert_eq!(r.counters.fixes, 2);
        // Line ends alone say nothing.
        assert!(r.push(b"\r\n\n\r\n").is_empty());
    }

    #[test]
    fn a_fix_off_the_globe_is_invalid_with_its_numbers() {
        let mut r = NmeaReader::new();
        // (NMEA latitudes have two degree digits: 100.67° cannot be written; longitudes
        // have three.)
        let found = r.push(sentences(45.5, 181.5, 12.5, 0.9, 10.0).as_bytes());
        let Sentence::Invalid(why) = &found[0] else {
            panic!("{found:?}");
        };
        assert!(
            why.ends_with(
                "fix off the globe: latitude 45.5° (expected within ±90), longitude 181.5° \
                 (expected within ±180)"
            ),
            "{why}"
        );
        // The RMC after it adds nothing (GGA is the fix sentence).
        assert_eq!((r.counters.fixes, r.counters.invalid), (0, 1), "{found:?}");
        // The nmea_sentences fuzz target's find (fuzz/regressions/nmea_sentences/): two
        // degree digits, and 96.23° all the same ("96" degrees, 14.038 minutes).
        let found =
            r.push(b"$GPGGA,061759.00,9614.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*69\r\n");
        assert!(
            matches!(&found[..], [Sentence::Invalid(why)] if why.contains("latitude 96.23")),
            "{found:?}"
        );
    }

    #[test]
    fn a_receiver_without_a_fix_is_valid_but_gives_no_fix() {
        let mut r = NmeaReader::new();
        let found = r.push(no_fix_sentences(45_296.5).as_bytes());
        assert_eq!(found, vec![Sentence::NoFix, Sentence::NoFix]);
        assert_eq!((r.counters.no_fix, r.counters.invalid), (2, 0));
    }
}
