//! One point-list parser: `id x y z` per line, for `poser project --points`, `points_file`
//! targets (a test field or GCP list) and the fuzz targets.
use glam::DVec3;

/// Split one CSV line into fields (RFC 4180 quotes).
fn split_csv(line: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    let mut was_quoted = false;
    while let Some(c) = chars.next() {
        if quoted {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    cur.push('"');
                    chars.next();
                } else {
                    quoted = false;
                }
            } else {
                cur.push(c);
            }
        } else if c == '"' && cur.trim().is_empty() {
            quoted = true;
            was_quoted = true;
            cur.clear();
        } else if c == ',' {
            out.push(if was_quoted {
                std::mem::take(&mut cur)
            } else {
                cur.trim().to_string()
            });
            cur.clear();
            was_quoted = false;
        } else {
            cur.push(c);
        }
    }
    if quoted {
        return Err("unterminated quoted field".into());
    }
    out.push(if was_quoted {
        cur
    } else {
        cur.trim().to_string()
    });
    Ok(out)
}

/// Parse the points file: `(id, point)` per data row.
pub fn parse_points(text: &str, file: &str) -> Result<Vec<(String, DVec3)>, String> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((hl, header)) = lines.next() else {
        return Err(format!(
            "{file}: empty file\nhelp: the first line must be the header `id,x,y,z`"
        ));
    };
    let cols: Vec<String> = split_csv(header.trim_start_matches('\u{feff}'))
        .map_err(|e| format!("{file}:{}: {e}", hl + 1))?
        .iter()
        .map(|c| c.to_ascii_lowercase())
        .collect();
    let find = |name: &str| cols.iter().position(|c| c == name);
    let (Some(ci), Some(cx), Some(cy), Some(cz)) = (find("id"), find("x"), find("y"), find("z"))
    else {
        return Err(format!(
            "{file}:{}: header `{}` lacks one of the columns id, x, y, z\nhelp: the first line must be `id,x,y,z` (metres)",
            hl + 1,
            header.trim()
        ));
    };
    let mut out = Vec::new();
    for (i, line) in lines {
        let f = split_csv(line).map_err(|e| format!("{file}:{}: {e}", i + 1))?;
        let get = |k: usize, what: &str| -> Result<f64, String> {
            let s = f
                .get(k)
                .ok_or_else(|| format!("{file}:{}: missing column `{what}`", i + 1))?;
            let v: f64 = s.parse().map_err(|_| {
                format!("{file}:{}: `{s}` is not a number (column `{what}`)", i + 1)
            })?;
            if !v.is_finite() {
                return Err(format!(
                    "{file}:{}: `{s}` is not a finite number (column `{what}`)",
                    i + 1
                ));
            }
            Ok(v)
        };
        let id = f
            .get(ci)
            .cloned()
            .ok_or_else(|| format!("{file}:{}: missing column `id`", i + 1))?;
        out.push((id, DVec3::new(get(cx, "x")?, get(cy, "y")?, get(cz, "z")?)));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_parsing_reports_line_numbers() {
        let pts = parse_points("id,x,y,z\n\"a,1\",1,2,3\nb, 4 ,5,6\n", "f.csv").unwrap();
        assert_eq!(pts[0].0, "a,1");
        assert_eq!(pts[1].1, DVec3::new(4.0, 5.0, 6.0));
        let e = parse_points("id,x,y,z\na,1,2\n", "f.csv").unwrap_err();
        assert!(e.starts_with("f.csv:2:"), "{e}");
        let e = parse_points("id,x,y,z\na,1,zz,3\n", "f.csv").unwrap_err();
        assert!(e.contains("`zz` is not a number"), "{e}");
        assert!(
            parse_points("name,x,y\n", "f.csv")
                .unwrap_err()
                .contains("help:")
        );
        assert!(parse_points("id,x,y,z\na,NaN,1,1\n", "f.csv").is_err());
        // Column order is taken from the header.
        let p = parse_points("z,y,x,id\n3,2,1,p\n", "f.csv").unwrap();
        assert_eq!(p[0], ("p".into(), DVec3::new(1.0, 2.0, 3.0)));
    }
}
