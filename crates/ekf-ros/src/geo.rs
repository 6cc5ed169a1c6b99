//! Positions on the globe and in the map: a local east-north tangent plane about an
//! origin on the WGS-84 ellipsoid, used by the GPS emulator (map → fix) and by GPS fusion
//! (fix → map).

/// WGS-84 semi-major axis (m).
const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 first eccentricity squared.
const WGS84_E2: f64 = 6.694_379_990_14e-3;

/// Where the simulated room lies on the globe: its frame's origin, x east, y north.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoOrigin {
    /// Latitude (degrees, north positive).
    pub latitude: f64,
    /// Longitude (degrees, east positive).
    pub longitude: f64,
    /// Altitude above mean sea level (m).
    pub altitude: f64,
}

impl GeoOrigin {
    /// The fix at `(east, north)` metres from the origin, on the WGS-84 ellipsoid's
    /// tangent plane there (meridian and prime-vertical radii of curvature; good to
    /// millimetres over a few hundred metres). No receiver noise is modelled.
    pub fn fix_at(&self, east: f64, north: f64) -> GeoFix {
        let phi = self.latitude.to_radians();
        let (meridian, prime_vertical) = self.radii();
        GeoFix {
            latitude: self.latitude + (north / meridian).to_degrees(),
            longitude: self.longitude + (east / (prime_vertical * phi.cos())).to_degrees(),
            altitude: self.altitude,
            hdop: 1.0,
        }
    }

    /// `(east, north)` metres from the origin of the point at `latitude`, `longitude`
    /// (degrees): the inverse of [`fix_at`](Self::fix_at).
    pub fn local(&self, latitude: f64, longitude: f64) -> (f64, f64) {
        let (meridian, prime_vertical) = self.radii();
        let phi = self.latitude.to_radians();
        (
            (longitude - self.longitude).to_radians() * prime_vertical * phi.cos(),
            (latitude - self.latitude).to_radians() * meridian,
        )
    }

    /// The meridian and prime-vertical radii of curvature at the origin (m).
    fn radii(&self) -> (f64, f64) {
        let phi = self.latitude.to_radians();
        let w = 1.0 - WGS84_E2 * phi.sin().powi(2);
        (WGS84_A * (1.0 - WGS84_E2) / w.powf(1.5), WGS84_A / w.sqrt())
    }
}

impl std::str::FromStr for GeoOrigin {
    type Err = String;

    /// `LAT,LON` or `LAT,LON,ALT` (degrees, degrees, metres).
    fn from_str(text: &str) -> Result<Self, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let number = |i: usize, what: &str| -> Result<f64, String> {
            parts[i]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{what} {:?} is not a number", parts[i]))
        };
        if !(2..=3).contains(&parts.len()) {
            return Err(format!("{text:?}: expected LAT,LON or LAT,LON,ALT"));
        }
        let origin = GeoOrigin {
            latitude: number(0, "latitude")?,
            longitude: number(1, "longitude")?,
            altitude: if parts.len() == 3 {
                number(2, "altitude")?
            } else {
                0.0
            },
        };
        if origin.latitude.abs() > 89.0 || origin.longitude.abs() > 180.0 {
            return Err(format!(
                "{text:?}: expected a latitude within ±89° and a longitude within ±180°"
            ));
        }
        Ok(origin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixes_lie_about_the_origin_and_origins_parse() {
        let o = GeoOrigin {
            latitude: 21.0,
            longitude: 105.8,
            altitude: 10.0,
        };
        // One arc minute of latitude is 1845.3 m at 21° N (geodetic tables).
        let f = o.fix_at(0.0, 1845.3);
        assert!(((f.latitude - 21.0) * 60.0 - 1.0).abs() < 1e-4, "{f:?}");
        assert_eq!("21, 105.8,10".parse::<GeoOrigin>(), Ok(o));
        assert!("21".parse::<GeoOrigin>().is_err());
        assert!("95,0"
            .parse::<GeoOrigin>()
            .unwrap_err()
            .contains("latitude"));
        let f = o.fix_at(100.0, 0.0);
        let east = (f.longitude - 105.8).to_radians() * WGS84_A * 21f64.to_radians().cos();
        assert!((east - 100.0).abs() < 0.5, "{east}");
    }

    #[test]
    fn local_inverts_fix_at() {
        let o = GeoOrigin {
            latitude: 10.77,
            longitude: 106.66,
            altitude: 5.0,
        };
        for (e, n) in [(0.0, 0.0), (120.5, -33.25), (-400.0, 250.0)] {
            let f = o.fix_at(e, n);
            let (e2, n2) = o.local(f.latitude, f.longitude);
            assert!((e2 - e).abs() < 1e-6 && (n2 - n).abs() < 1e-6, "{e2} {n2}");
        }
        // One arc-second of latitude is about 30.7 m there.
        let (_, n) = o.local(10.77 + 1.0 / 3600.0, 106.66);
        assert!((n - 30.7).abs() < 0.1, "{n}");
    }
}

/// A GPS position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoFix {
    /// Latitude (degrees).
    pub latitude: f64,
    /// Longitude (degrees).
    pub longitude: f64,
    /// Altitude (m).
    pub altitude: f64,
    /// Horizontal dilution of precision.
    pub hdop: f64,
}
