//! Physical units in scene files: parse `"18 mm"`, `"0.2 m/s"`, `"232 bar"` into SI numbers.
//!
//! A scene value with a physical dimension may be written as a plain number (already in the SI
//! unit of that dimension, see [`Dim::si_unit`]) or as a string `"<number> <unit>"`. Vectors may
//! be written as arrays of such values or as one string with a trailing unit (`"0, 0.1, 2 m"`).
//!
//! | dimension | SI unit (plain numbers) | units accepted in strings |
//! |---|---|---|
//! | length | m | `m`, `cm`, `mm`, `µm`/`um`, `nm`, `km`, `ft`, `in` |
//! | angle | rad | `rad`, `mrad`, `deg`/`°` |
//! | speed | m/s | `m/s`, `cm/s`, `m/min`, `ft/min`, `km/h`, `kn` |
//! | flow (gas use) | m³/s | `l/min`, `L/min`, `m3/s`, `m³/s`, `cuft/min` |
//! | pressure | Pa | `Pa`, `kPa`, `MPa`, `bar`, `mbar`, `psi`, `atm` |
//! | volume | m³ | `m3`, `m³`, `l`, `L`, `ml`, `cuft` |
//! | time | s | `s`, `ms`, `min`, `h` |
//! | power | W | `W`, `mW`, `kW` |
//! | intensity | W/sr | `W/sr`, `mW/sr` |
//! | radiance | W/(m²·sr) | `W/m2/sr`, `W/(m2 sr)`, `W/m²/sr` |
//! | irradiance | W/m² | `W/m2`, `W/m²` |
//! | temperature | °C | `C`, `°C`, `degC`, `K`, `F`, `°F` |
//! | fraction | 1 | `%` |
//! | GSD | m/px | `m/px`, `cm/px`, `mm/px` |
//!
//! Units are case-exact, as SI writes them: `mW` is a milliwatt and `MW` would be a megawatt,
//! so `"50 MW"` is an error, never 50 mW. Only spellings without an SI prefix, where case
//! cannot change the meaning (`Bar`, `PSI`, `Deg`, `FT`, `Min`, …; see [`CASE_FREE`]), are
//! also accepted in another case.

/// A physical dimension a scene value can have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    Length,
    Angle,
    Speed,
    Flow,
    Pressure,
    Volume,
    Time,
    Power,
    Intensity,
    Radiance,
    Irradiance,
    Temperature,
    Fraction,
    Gsd,
    /// A pure number (no unit allowed).
    Number,
}

impl Dim {
    /// The unit plain numbers are read in.
    pub fn si_unit(self) -> &'static str {
        match self {
            Dim::Length => "m",
            Dim::Angle => "rad",
            Dim::Speed => "m/s",
            Dim::Flow => "m³/s",
            Dim::Pressure => "Pa",
            Dim::Volume => "m³",
            Dim::Time => "s",
            Dim::Power => "W",
            Dim::Intensity => "W/sr",
            Dim::Radiance => "W/(m²·sr)",
            Dim::Irradiance => "W/m²",
            Dim::Temperature => "°C",
            Dim::Fraction => "fraction (0..1)",
            Dim::Gsd => "m/px",
            Dim::Number => "1",
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Dim::Length => "length",
            Dim::Angle => "angle",
            Dim::Speed => "speed",
            Dim::Flow => "gas flow",
            Dim::Pressure => "pressure",
            Dim::Volume => "volume",
            Dim::Time => "time",
            Dim::Power => "power",
            Dim::Intensity => "radiant intensity",
            Dim::Radiance => "radiance",
            Dim::Irradiance => "irradiance",
            Dim::Temperature => "temperature",
            Dim::Fraction => "fraction",
            Dim::Gsd => "ground sampling distance",
            Dim::Number => "number",
        }
    }
    /// Units accepted in strings: (spelling, factor to SI, offset added after scaling).
    fn units(self) -> &'static [(&'static str, f64, f64)] {
        const FT: f64 = 0.3048;
        match self {
            Dim::Length => &[
                ("m", 1.0, 0.0),
                ("cm", 1e-2, 0.0),
                ("mm", 1e-3, 0.0),
                ("µm", 1e-6, 0.0),
                ("μm", 1e-6, 0.0),
                ("um", 1e-6, 0.0),
                ("nm", 1e-9, 0.0),
                ("km", 1e3, 0.0),
                ("ft", FT, 0.0),
                ("in", 0.0254, 0.0),
            ],
            Dim::Angle => &[
                ("rad", 1.0, 0.0),
                ("mrad", 1e-3, 0.0),
                ("deg", std::f64::consts::PI / 180.0, 0.0),
                ("°", std::f64::consts::PI / 180.0, 0.0),
            ],
            Dim::Speed => &[
                ("m/s", 1.0, 0.0),
                ("cm/s", 1e-2, 0.0),
                ("m/min", 1.0 / 60.0, 0.0),
                ("ft/min", FT / 60.0, 0.0),
                ("km/h", 1.0 / 3.6, 0.0),
                ("kn", 1852.0 / 3600.0, 0.0),
            ],
            Dim::Flow => &[
                ("m3/s", 1.0, 0.0),
                ("m³/s", 1.0, 0.0),
                ("l/min", 1e-3 / 60.0, 0.0),
                ("L/min", 1e-3 / 60.0, 0.0),
                ("cuft/min", 0.028316846592 / 60.0, 0.0),
            ],
            Dim::Pressure => &[
                ("Pa", 1.0, 0.0),
                ("kPa", 1e3, 0.0),
                ("MPa", 1e6, 0.0),
                ("bar", 1e5, 0.0),
                ("mbar", 1e2, 0.0),
                ("psi", 6894.757293168, 0.0),
                ("atm", 101325.0, 0.0),
            ],
            Dim::Volume => &[
                ("m3", 1.0, 0.0),
                ("m³", 1.0, 0.0),
                ("l", 1e-3, 0.0),
                ("L", 1e-3, 0.0),
                ("ml", 1e-6, 0.0),
                ("cuft", 0.028316846592, 0.0),
            ],
            Dim::Time => &[
                ("s", 1.0, 0.0),
                ("ms", 1e-3, 0.0),
                ("min", 60.0, 0.0),
                ("h", 3600.0, 0.0),
            ],
            Dim::Power => &[("W", 1.0, 0.0), ("mW", 1e-3, 0.0), ("kW", 1e3, 0.0)],
            Dim::Intensity => &[("W/sr", 1.0, 0.0), ("mW/sr", 1e-3, 0.0)],
            Dim::Radiance => &[
                ("W/m2/sr", 1.0, 0.0),
                ("W/m²/sr", 1.0, 0.0),
                ("W/(m2 sr)", 1.0, 0.0),
                ("W/(m²·sr)", 1.0, 0.0),
            ],
            Dim::Irradiance => &[("W/m2", 1.0, 0.0), ("W/m²", 1.0, 0.0)],
            Dim::Temperature => &[
                ("C", 1.0, 0.0),
                ("°C", 1.0, 0.0),
                ("degC", 1.0, 0.0),
                ("K", 1.0, -273.15),
                ("F", 5.0 / 9.0, -32.0 * 5.0 / 9.0),
                ("°F", 5.0 / 9.0, -32.0 * 5.0 / 9.0),
            ],
            Dim::Fraction => &[("%", 0.01, 0.0)],
            Dim::Gsd => &[
                ("m/px", 1.0, 0.0),
                ("cm/px", 1e-2, 0.0),
                ("mm/px", 1e-3, 0.0),
            ],
            Dim::Number => &[],
        }
    }
    /// Spellings accepted for this dimension, for messages.
    pub fn unit_list(self) -> String {
        self.units()
            .iter()
            .map(|u| u.0)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Canonical spellings that are accepted in any letter case: none carries an SI prefix, so
/// case cannot change their meaning (`"Bar"`, `"PSI"`, `"DEG"`). Every other unit is
/// case-exact (`m`/`M`, `k`, `G`, `T`, `P` are different prefixes).
pub const CASE_FREE: &[&str] = &[
    "bar", "psi", "atm", "deg", "rad", "ft", "in", "cuft", "cuft/min", "ft/min", "kn", "min",
    "degC", "°C", "°F",
];

/// Why a quantity string could not be read.
#[derive(Debug, Clone, PartialEq)]
pub enum UnitError {
    /// The number part is missing or malformed.
    BadNumber(String),
    /// No unit, or a unit of another dimension / unknown unit. `suggestion`: closest known unit.
    BadUnit {
        unit: String,
        dim: Dim,
        suggestion: Option<String>,
        other_dim: Option<Dim>,
        /// A known unit of this dimension that differs only in letter case, refused because
        /// case changes an SI prefix (`MW` for `mW`).
        case_of: Option<String>,
    },
    /// The result is NaN or infinite.
    NotFinite,
}

impl std::fmt::Display for UnitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            UnitError::BadNumber(s) => write!(f, "`{s}` is not a number"),
            UnitError::BadUnit {
                unit,
                dim,
                other_dim,
                case_of,
                ..
            } => {
                if let Some(c) = case_of {
                    write!(
                        f,
                        "unknown unit `{unit}` for a {}: units are case-sensitive (`{c}` is a different unit)",
                        dim.name()
                    )
                } else if let Some(o) = other_dim {
                    write!(
                        f,
                        "`{unit}` is a unit of {}, but a {} is expected",
                        o.name(),
                        dim.name()
                    )
                } else if unit.is_empty() {
                    write!(f, "a {} needs a unit", dim.name())
                } else {
                    write!(f, "unknown unit `{unit}` for a {}", dim.name())
                }
            }
            UnitError::NotFinite => write!(f, "the value is not a finite number"),
        }
    }
}

impl Dim {
    /// Every dimension with units.
    pub const ALL: &'static [Dim] = ALL_DIMS;
}

const ALL_DIMS: &[Dim] = &[
    Dim::Length,
    Dim::Angle,
    Dim::Speed,
    Dim::Flow,
    Dim::Pressure,
    Dim::Volume,
    Dim::Time,
    Dim::Power,
    Dim::Intensity,
    Dim::Radiance,
    Dim::Irradiance,
    Dim::Temperature,
    Dim::Fraction,
    Dim::Gsd,
];

fn parse_number(s: &str) -> Result<f64, UnitError> {
    let t = s.trim().replace('_', "");
    let ok = !t.is_empty()
        && t.chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E'));
    match t.parse::<f64>() {
        Ok(v) if ok => {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(UnitError::NotFinite)
            }
        }
        _ => Err(UnitError::BadNumber(s.trim().to_string())),
    }
}

/// Split `"18 mm"` / `"18mm"` / `"-3.5e-3 m/s"` into number text and unit text.
fn split(s: &str) -> (&str, &str) {
    let s = s.trim();
    let mut end = 0;
    let b: Vec<(usize, char)> = s.char_indices().collect();
    let mut i = 0;
    while i < b.len() {
        let c = b[i].1;
        let is_exp = (c == 'e' || c == 'E')
            && i + 1 < b.len()
            && (b[i + 1].1.is_ascii_digit() || b[i + 1].1 == '-' || b[i + 1].1 == '+')
            && i > 0;
        if c.is_ascii_digit()
            || c == '.'
            || c == '_'
            || ((c == '-' || c == '+') && (i == 0 || matches!(b[i - 1].1, 'e' | 'E')))
        {
            i += 1;
            end = b.get(i).map(|x| x.0).unwrap_or(s.len());
        } else if is_exp {
            i += 1;
        } else {
            break;
        }
    }
    (&s[..end], s[end..].trim())
}

fn normalise_unit(u: &str) -> String {
    u.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Parse a unit string for a dimension, returning (factor, offset).
fn unit_factor(unit: &str, dim: Dim) -> Result<(f64, f64), UnitError> {
    let u = normalise_unit(unit);
    if let Some(&(_, f, o)) = dim.units().iter().find(|x| x.0 == u) {
        return Ok((f, o));
    }
    // Another letter case: accepted only for prefix-free spellings ("Bar", "PSI").
    let ci: Vec<_> = dim
        .units()
        .iter()
        .filter(|x| x.0.eq_ignore_ascii_case(&u))
        .collect();
    if ci.len() == 1 && !u.is_empty() && CASE_FREE.contains(&ci[0].0) {
        return Ok((ci[0].1, ci[0].2));
    }
    let case_of = ci.first().map(|x| x.0.to_string());
    let other_dim = ALL_DIMS
        .iter()
        .copied()
        .find(|d| *d != dim && d.units().iter().any(|x| x.0 == u));
    let suggestion = dim
        .units()
        .iter()
        .map(|x| (strsim::jaro_winkler(x.0, &u), x.0))
        .filter(|(s, _)| *s > 0.7)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|x| x.1.to_string());
    Err(UnitError::BadUnit {
        unit: u,
        dim,
        suggestion: case_of.clone().or(suggestion),
        other_dim,
        case_of,
    })
}

/// Parse `"<number> <unit>"` as a quantity of dimension `dim`, in SI. A bare number in a
/// string (`"18"`) is read in the SI unit, like a TOML number.
pub fn parse_quantity(s: &str, dim: Dim) -> Result<f64, UnitError> {
    let (num, unit) = split(s);
    if num.is_empty() {
        return Err(UnitError::BadNumber(s.trim().to_string()));
    }
    let v = parse_number(num)?;
    if unit.is_empty() {
        return Ok(v);
    }
    if dim == Dim::Number {
        return Err(UnitError::BadUnit {
            unit: unit.into(),
            dim,
            suggestion: None,
            other_dim: None,
            case_of: None,
        });
    }
    let (f, o) = unit_factor(unit, dim)?;
    let r = v * f + o;
    if r.is_finite() {
        Ok(r)
    } else {
        Err(UnitError::NotFinite)
    }
}

/// Parse a vector string with one trailing unit: `"0, 0.1, 2 m"` or `"10 20 30 deg"`.
pub fn parse_vector(s: &str, dim: Dim) -> Result<Vec<f64>, UnitError> {
    let s = s.trim().trim_start_matches('[');
    // The unit is whatever follows the last number.
    let parts: Vec<&str> = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|p| !p.is_empty())
        .collect();
    let mut nums = Vec::new();
    let mut unit = String::new();
    for (i, p) in parts.iter().enumerate() {
        let p = p.trim_end_matches(']');
        let (n, u) = split(p);
        if n.is_empty() || !unit.is_empty() {
            unit = parts[i..].join(" ").trim_end_matches(']').to_string();
            if !n.is_empty() && !u.is_empty() {
                unit = u.to_string();
            }
            break;
        }
        nums.push(parse_number(n)?);
        if !u.is_empty() {
            unit = std::iter::once(u)
                .chain(parts[i + 1..].iter().copied())
                .collect::<Vec<_>>()
                .join(" ");
            break;
        }
    }
    if nums.is_empty() {
        return Err(UnitError::BadNumber(s.to_string()));
    }
    if unit.is_empty() {
        return Ok(nums);
    }
    let (f, o) = unit_factor(&unit, dim)?;
    let out: Vec<f64> = nums.iter().map(|v| v * f + o).collect();
    if out.iter().all(|v| v.is_finite()) {
        Ok(out)
    } else {
        Err(UnitError::NotFinite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(s: &str, d: Dim) -> f64 {
        parse_quantity(s, d).unwrap()
    }

    #[test]
    fn common_units() {
        // Tolerance 1e-12 relative: pure scaling, only rounding in the factors.
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-300);
        assert!(close(q("18 mm", Dim::Length), 0.018));
        assert!(close(q("15 m", Dim::Length), 15.0));
        assert!(close(q("0.2 m/s", Dim::Speed), 0.2));
        assert!(close(q("20 l/min", Dim::Flow), 20e-3 / 60.0));
        assert!(close(q("532 nm", Dim::Length), 532e-9));
        assert!(close(q("30 deg", Dim::Angle), std::f64::consts::PI / 6.0));
        assert!(close(q("232 bar", Dim::Pressure), 232e5));
        assert!(close(q("12 l", Dim::Volume), 0.012));
        assert!(close(q("50 W", Dim::Power), 50.0));
        assert!(close(q("4.5 µm", Dim::Length), 4.5e-6));
        assert!(close(q("4.5um", Dim::Length), 4.5e-6));
        assert!(close(q("-2.5e-3 m", Dim::Length), -2.5e-3));
        assert!(close(q("60 %", Dim::Fraction), 0.6));
        assert!(close(q("18 m/min", Dim::Speed), 0.3));
        assert!(close(q("293.15 K", Dim::Temperature), 20.0));
        assert!(close(q("1_000 mm", Dim::Length), 1.0));
    }

    #[test]
    fn errors() {
        assert!(matches!(
            parse_quantity("18 bar", Dim::Length),
            Err(UnitError::BadUnit {
                other_dim: Some(Dim::Pressure),
                ..
            })
        ));
        match parse_quantity("18 mmm", Dim::Length) {
            Err(UnitError::BadUnit {
                suggestion: Some(s),
                ..
            }) => assert_eq!(s, "mm"),
            e => panic!("{e:?}"),
        }
        assert!(matches!(
            parse_quantity("abc m", Dim::Length),
            Err(UnitError::BadNumber(_))
        ));
        assert!(matches!(
            parse_quantity("", Dim::Length),
            Err(UnitError::BadNumber(_))
        ));
        assert!(parse_quantity("1e400 m", Dim::Length).is_err());
        assert!(parse_quantity("3 m", Dim::Number).is_err());
    }

    /// SI prefixes are case-exact: `"50 MW"` is not 50 mW (a factor of 10⁹), `"1 mPa"` is not
    /// 1 MPa, `"3 MM"` is not 3 mm; prefix-free spellings still accept any case.
    #[test]
    fn units_are_case_exact_where_si_says_so() {
        for (s, d, hint) in [
            ("50 MW", Dim::Power, "mW"),
            ("1 mpa", Dim::Pressure, "MPa"),
            ("3 MM", Dim::Length, "mm"),
            ("2 KM", Dim::Length, "km"),
            ("5 Kw", Dim::Power, "kW"),
            ("1 M", Dim::Length, "m"),
        ] {
            match parse_quantity(s, d) {
                Err(e @ UnitError::BadUnit { .. }) => {
                    let UnitError::BadUnit {
                        case_of,
                        suggestion,
                        ..
                    } = &e
                    else {
                        unreachable!()
                    };
                    assert_eq!(case_of.as_deref(), Some(hint), "{s}");
                    assert_eq!(suggestion.as_deref(), Some(hint), "{s}");
                    assert!(e.to_string().contains("case-sensitive"), "{e}");
                }
                r => panic!("{s}: expected a unit error, got {r:?}"),
            }
        }
        assert!(parse_vector("1, 2, 3 MM", Dim::Length).is_err());
        // Prefix-free spellings: any case.
        assert_eq!(q("232 Bar", Dim::Pressure), 232e5);
        assert_eq!(q("1 ATM", Dim::Pressure), 101325.0);
        assert_eq!(q("10 FT", Dim::Length), 3.048);
        assert_eq!(q("2 Min", Dim::Time), 120.0);
        assert!((q("90 DEG", Dim::Angle) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        // Both spellings of litre are listed, so both stay exact.
        assert_eq!(q("12 L", Dim::Volume), q("12 l", Dim::Volume));
    }

    #[test]
    fn vectors() {
        assert_eq!(
            parse_vector("0, 10, 2000 mm", Dim::Length).unwrap(),
            vec![0.0, 0.01, 2.0]
        );
        assert_eq!(
            parse_vector("1 2 3", Dim::Length).unwrap(),
            vec![1.0, 2.0, 3.0]
        );
        let v = parse_vector("90, 0, 0 deg", Dim::Angle).unwrap();
        assert!((v[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!(parse_vector("1, 2, 3 bar", Dim::Length).is_err());
    }
}
