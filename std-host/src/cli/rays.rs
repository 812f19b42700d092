//! Reading batches of rays from CSV: the input of `rdbvh trace`.
//!
//! The format is what a user can write from any tool: a header naming the columns, found by name
//! in any order, `ox,oy,oz,dx,dy,dz` required and `tmin,tmax` optional (defaults 0 and +inf).
//! Numbers are Rust `f32` literals, which include `inf`, `-inf` and `infinity`. Every bad row is an
//! error naming its line, never a skipped row: a silently dropped ray would shift every following
//! ray's index in the output.

use std::fmt;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use rdbvh_core::geometry::Ray;
use rdbvh_core::Vec3;

/// The required columns, in the order the ray takes them.
pub const REQUIRED_COLUMNS: [&str; 6] = ["ox", "oy", "oz", "dx", "dy", "dz"];
/// The optional columns: segment start and end.
pub const OPTIONAL_COLUMNS: [&str; 2] = ["tmin", "tmax"];

/// A rays file that cannot be used.
#[derive(Debug)]
pub struct RaysError {
    /// The rays file.
    pub path: PathBuf,
    /// 1-based line in the file, when the problem is on one line.
    pub line: Option<u64>,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for RaysError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{} line {line}: {}", self.path.display(), self.reason),
            None => write!(f, "{}: {}", self.path.display(), self.reason),
        }
    }
}

impl std::error::Error for RaysError {}

/// Reads every ray of the CSV file at `path`.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, RaysError> {
    let file = File::open(path).map_err(|e| RaysError {
        path: path.to_path_buf(),
        line: None,
        reason: format!("cannot open: {e}"),
    })?;
    parse_rays(file, path)
}

/// Reads every ray of CSV text from `reader`; `label` names it in errors.
pub fn parse_rays(reader: impl Read, label: &Path) -> Result<Vec<Ray>, RaysError> {
    let error = |line: Option<u64>, reason: String| RaysError {
        path: label.to_path_buf(),
        line,
        reason,
    };
    // Headers are trimmed by the reader, fields where they are read: the reader's own trimming of
    // a whole record copies it into a new allocation per row (a tenth of reading 1M rays).
    let mut csv = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::Headers)
        .from_reader(reader);
    let header = csv
        .headers()
        .map_err(|e| error(Some(1), csv_reason(&e)))?
        .clone();
    if header.iter().all(str::is_empty) {
        return Err(error(
            None,
            format!(
                "missing header line (expected at least {})",
                REQUIRED_COLUMNS.join(",")
            ),
        ));
    }
    let column = |name: &str| -> Result<Option<usize>, RaysError> {
        let mut found = header
            .iter()
            .enumerate()
            .filter(|(_, h)| h.eq_ignore_ascii_case(name));
        let first = found.next().map(|(i, _)| i);
        if found.next().is_some() {
            return Err(error(Some(1), format!("column '{name}' appears twice")));
        }
        Ok(first)
    };
    let mut required = [0usize; 6];
    for (slot, name) in required.iter_mut().zip(REQUIRED_COLUMNS) {
        *slot = column(name)?.ok_or_else(|| {
            error(
                Some(1),
                format!(
                    "missing column '{name}' (the header must name {}, optionally tmin,tmax)",
                    REQUIRED_COLUMNS.join(",")
                ),
            )
        })?;
    }
    let tmin = column(OPTIONAL_COLUMNS[0])?;
    let tmax = column(OPTIONAL_COLUMNS[1])?;

    let mut rays = Vec::new();
    let mut record = csv::StringRecord::new();
    loop {
        match csv.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e.position().map(|p| p.line());
                return Err(error(line, csv_reason(&e)));
            }
        }
        let line = record.position().map(|p| p.line());
        let ray_index = rays.len();
        let field = |i: usize, name: &str| -> Result<Option<f32>, RaysError> {
            let text = record.get(i).unwrap_or("").trim();
            if text.is_empty() {
                return Ok(None);
            }
            text.parse::<f32>().map(Some).map_err(|_| {
                // Echoed escaped and cut short: a quoted cell may hold newlines or a whole file.
                let shown: String = text.chars().take(40).collect();
                let more = if text.chars().count() > 40 { "..." } else { "" };
                error(
                    line,
                    format!(
                        "ray {ray_index}: column '{name}': cannot parse '{}{more}' as a number",
                        shown.escape_debug()
                    ),
                )
            })
        };
        let mut v = [0.0f32; 6];
        for ((value, &i), name) in v.iter_mut().zip(&required).zip(REQUIRED_COLUMNS) {
            *value = field(i, name)?
                .ok_or_else(|| error(line, format!("ray {ray_index}: column '{name}' is empty")))?;
        }
        // An empty tmin/tmax cell means the default, like a missing column.
        let t_min = match tmin {
            Some(i) => field(i, "tmin")?.unwrap_or(0.0),
            None => 0.0,
        };
        let t_max = match tmax {
            Some(i) => field(i, "tmax")?.unwrap_or(f32::INFINITY),
            None => f32::INFINITY,
        };
        let origin = Vec3::new(v[0], v[1], v[2]);
        let dir = Vec3::new(v[3], v[4], v[5]);
        let ray = Ray::segment(origin, dir, t_min, t_max)
            .map_err(|e| error(line, format!("ray {ray_index}: {e}")))?;
        rays.push(ray);
    }
    Ok(rays)
}

/// A CSV error without the crate's own position prefix (ours names the line).
fn csv_reason(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!("has {len} fields, but the header has {expected_len}"),
        csv::ErrorKind::Utf8 { .. } => "not valid UTF-8".to_string(),
        csv::ErrorKind::Io(io) => format!("cannot read: {io}"),
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<Ray>, RaysError> {
        parse_rays(text.as_bytes(), Path::new("rays.csv"))
    }

    fn line_of(text: &str) -> Option<u64> {
        parse(text).expect_err("should fail").line
    }

    #[test]
    fn minimal_columns_default_the_segment() {
        let rays = parse("ox,oy,oz,dx,dy,dz\n0,0,0,0,0,1\n1,2,3,-1,0,0\n").unwrap();
        assert_eq!(rays.len(), 2);
        assert_eq!(rays[0].t_min, 0.0);
        assert_eq!(rays[0].t_max, f32::INFINITY);
        assert_eq!(rays[1].origin, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(rays[1].dir, -Vec3::X);
    }

    #[test]
    fn fields_are_trimmed_quoted_or_not() {
        let rays = parse("ox,oy,oz,dx,dy,dz,tmax\n 1 ,2,\t3 ,\" 0\",0, 1 ,  \n").unwrap();
        assert_eq!(rays[0].origin, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(rays[0].dir, Vec3::Z);
        assert_eq!(rays[0].t_max, f32::INFINITY);
        let e = parse("ox,oy,oz,dx,dy,dz\n1,2,3,0,0, x \n").unwrap_err();
        assert!(e.reason.contains("cannot parse 'x'"), "{}", e.reason);
    }

    #[test]
    fn columns_by_name_in_any_order() {
        let text = "tmax, dz ,dy,DX,oz,oy,ox,tmin,note\ninf,3,2,1,6,5,4,0.5,x\n7,1,0,0,0,0,0,,\n";
        let rays = parse(text).unwrap();
        assert_eq!(rays[0].origin, Vec3::new(4.0, 5.0, 6.0));
        assert_eq!(rays[0].dir, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!((rays[0].t_min, rays[0].t_max), (0.5, f32::INFINITY));
        assert_eq!((rays[1].t_min, rays[1].t_max), (0.0, 7.0));
    }

    #[test]
    fn numbers_round_trip_exactly() {
        let x = 0.1f32 + 1e-7;
        let rays = parse(&format!("ox,oy,oz,dx,dy,dz\n{x},-0,1e-3,1,0,0\n")).unwrap();
        assert_eq!(rays[0].origin.x, x);
    }

    #[test]
    fn empty_segment_is_valid() {
        let rays = parse("ox,oy,oz,dx,dy,dz,tmin,tmax\n0,0,0,1,0,0,2,1\n").unwrap();
        assert!(rays[0].t_min > rays[0].t_max);
    }

    #[test]
    fn header_only_is_no_rays() {
        assert!(parse("ox,oy,oz,dx,dy,dz\n").unwrap().is_empty());
    }

    #[test]
    fn bad_rows_name_their_line() {
        let h = "ox,oy,oz,dx,dy,dz,tmin,tmax\n";
        let ok = "0,0,0,1,0,0,0,1\n";
        for (bad, why) in [
            ("0,0,0,0,0,0,0,1\n", "zero"),
            ("nan,0,0,1,0,0,0,1\n", "NaN"),
            ("0,0,0,1,0,0,nan,1\n", "NaN"),
            ("inf,0,0,1,0,0,0,1\n", "infinite"),
            ("0,0,0,1,x,0,0,1\n", "cannot parse"),
            ("0,0,0,1,0,0,0\n", "fields"),
            ("0,0,,1,0,0,0,1\n", "empty"),
        ] {
            let text = format!("{h}{ok}{ok}{bad}{ok}");
            let e = parse(&text).expect_err(bad);
            assert_eq!(e.line, Some(4), "{bad}: {e}");
            assert!(e.to_string().contains(why), "{bad}: {e}");
            assert!(e.to_string().contains("rays.csv line 4: "), "{e}");
        }
    }

    /// A quoted cell can hold newlines (found by the parsers fuzz target): the error echoes it
    /// escaped and cut short, so it stays one line.
    #[test]
    fn unparsable_cell_is_echoed_on_one_line() {
        let long = "x\n".repeat(100);
        let e = parse(&format!("ox,oy,oz,dx,dy,dz\n0,0,0,1,\"{long}\",0\n")).unwrap_err();
        let m = e.to_string();
        assert!(
            !m.contains('\n') && m.contains("cannot parse") && m.contains("..."),
            "{m}"
        );
    }

    #[test]
    fn bad_headers() {
        assert!(parse("")
            .unwrap_err()
            .to_string()
            .contains("missing header"));
        assert!(line_of("ox,oy,oz,dx,dy\n0,0,0,1,0\n") == Some(1));
        let e = parse("ox,oy,oz,dx,dy,dz,ox\n").unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
    }
}
