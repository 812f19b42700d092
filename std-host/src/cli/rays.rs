//! Batches of rays in CSV: the input of `rdbvh trace` (and of `analyze` and `experiment` with
//! `--recorded-rays`), and what `rdbvh render --record-rays` writes.
//!
//! The format is what a user can write from any tool: a header naming the columns, found by name
//! in any order, `ox,oy,oz,dx,dy,dz` required and `tmin,tmax` optional (defaults 0 and +inf).
//! Numbers are Rust `f32` literals, which include `inf`, `-inf` and `infinity`. Every bad row is an
//! error naming its line, never a skipped row: a silently dropped ray would shift every following
//! ray's index in the output.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::error::CliError;
use crate::experiment::RaySource;
use crate::text_lines::line_at;

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

/// Writes `rays` as CSV with every column, `ox,oy,oz,dx,dy,dz,tmin,tmax`, in Rust's shortest
/// float formatting that reads back exactly: [`read_rays`] gives back the same rays, bit for bit (an
/// infinite `tmax` is written `inf`).
pub fn write_rays<'a>(
    out: &mut impl std::io::Write,
    rays: impl IntoIterator<Item = &'a Ray>,
) -> std::io::Result<()> {
    writeln!(
        out,
        "{},{}",
        REQUIRED_COLUMNS.join(","),
        OPTIONAL_COLUMNS.join(",")
    )?;
    for r in rays {
        let (o, d) = (r.origin, r.dir);
        writeln!(
            out,
            "{},{},{},{},{},{},{},{}",
            o.x, o.y, o.z, d.x, d.y, d.z, r.t_min, r.t_max
        )?;
    }
    Ok(())
}

/// Reads every ray of the CSV file at `path`.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, RaysError> {
    let text = std::fs::read(path).map_err(|e| RaysError {
        path: path.to_path_buf(),
        line: None,
        reason: format!("cannot open: {e}"),
    })?;
    parse_text(&text, path, PIECE_BYTES)
}

/// The ray source of `analyze` and `experiment`: the rays of `--recorded-rays FILE.csv` when it
/// is given, else the areas' samplers. A file with no ray is an error (there would be nothing to
/// measure).
pub fn ray_source(recorded: Option<&Path>) -> Result<RaySource, CliError> {
    let Some(path) = recorded else {
        return Ok(RaySource::Sampled);
    };
    let rays = read_rays(path)?;
    if rays.is_empty() {
        return Err(RaysError {
            path: path.to_path_buf(),
            line: None,
            reason: "holds no ray (--recorded-rays needs at least one)".into(),
        }
        .into());
    }
    Ok(RaySource::Recorded {
        path: path.to_path_buf(),
        rays,
    })
}

/// Reads every ray of CSV text from `reader`; `label` names it in errors.
///
/// The text is read whole, then parsed on every thread when it can be cut at line feeds without
/// changing what a row is: when it holds no quote (a quoted cell may hold a line end) and is over
/// 2 MiB. Each piece goes through the same CSV reader and the same checks, and the first error
/// in the file is reported with the line and ray index the one-thread read gives (a test holds
/// the two to the same rays and errors). Other text is read on one thread.
pub fn parse_rays(mut reader: impl Read, label: &Path) -> Result<Vec<Ray>, RaysError> {
    let mut text = Vec::new();
    reader.read_to_end(&mut text).map_err(|e| RaysError {
        path: label.to_path_buf(),
        line: None,
        reason: format!("cannot read: {e}"),
    })?;
    parse_text(&text, label, PIECE_BYTES)
}

/// Text below this many bytes per piece is not worth a thread: pieces are at least this long.
const PIECE_BYTES: usize = 1 << 20;

/// Where a rays file keeps each value.
struct Columns {
    /// The header's field count: every row must have as many.
    fields: usize,
    /// `ox, oy, oz, dx, dy, dz`.
    required: [usize; 6],
    tmin: Option<usize>,
    tmax: Option<usize>,
}

/// A bad row: the offset in the text where it starts (when known), the 0-based index of its
/// ray, and what is wrong (about that ray when `of_ray`, prefixed `ray N: ` once the index is
/// final).
struct RowError {
    at: Option<u64>,
    ray: usize,
    of_ray: bool,
    reason: String,
}

impl RowError {
    fn into_error(self, text: &[u8], label: &Path) -> RaysError {
        let reason = if self.of_ray {
            format!("ray {}: {}", self.ray, self.reason)
        } else {
            self.reason
        };
        RaysError {
            path: label.to_path_buf(),
            line: self.at.map(|at| line_at(text, at)),
            reason,
        }
    }
}

/// [`parse_rays`] over text in memory, cut into pieces of at least `piece` bytes when it can be.
fn parse_text(text: &[u8], label: &Path, piece: usize) -> Result<Vec<Ray>, RaysError> {
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
        .from_reader(text);
    let header = csv
        .headers()
        .map_err(|e| {
            let at = e.position().map_or(0, |p| p.byte());
            error(Some(line_at(text, at)), csv_reason(&e))
        })?
        .clone();
    // Blank lines before the header are skipped, so it need not be on line 1.
    let header_line = Some(line_at(text, header.position().map_or(0, |p| p.byte())));
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
            return Err(error(header_line, format!("column '{name}' appears twice")));
        }
        Ok(first)
    };
    let mut required = [0usize; 6];
    for (slot, name) in required.iter_mut().zip(REQUIRED_COLUMNS) {
        *slot = column(name)?.ok_or_else(|| {
            error(
                header_line,
                format!(
                    "missing column '{name}' (the header must name {}, optionally tmin,tmax)",
                    REQUIRED_COLUMNS.join(",")
                ),
            )
        })?;
    }
    let columns = Columns {
        fields: header.len(),
        required,
        tmin: column(OPTIONAL_COLUMNS[0])?,
        tmax: column(OPTIONAL_COLUMNS[1])?,
    };
    // Other columns are allowed (an id, say) but said: a misspelt `t_max` would otherwise turn
    // every segment into a whole ray without a word.
    for name in header.iter().filter(|h| {
        !h.is_empty()
            && !REQUIRED_COLUMNS
                .iter()
                .chain(&OPTIONAL_COLUMNS)
                .any(|c| h.eq_ignore_ascii_case(c))
    }) {
        eprintln!(
            "warning: {}: column '{name}' is not read (rays take {}, optionally {})",
            label.display(),
            REQUIRED_COLUMNS.join(","),
            OPTIONAL_COLUMNS.join(",")
        );
    }
    // Where the reader stands after the header (past any blank lines before it and its line end).
    let body = usize::try_from(csv.position().byte()).unwrap_or(usize::MAX);
    let pieces = match pieces(text, body, piece) {
        Some(p) if p.len() > 1 => p,
        _ => {
            // One thread: the header's reader reads on.
            let mut rays = Vec::new();
            read_rows(&mut csv, &columns, 0, &mut rays).map_err(|e| e.into_error(text, label))?;
            return Ok(rays);
        }
    };
    let mut parsed: Vec<(Vec<Ray>, Option<RowError>)> = pieces
        .par_iter()
        .map(|&(start, end)| {
            let mut csv = csv::ReaderBuilder::new()
                .has_headers(false)
                .flexible(true)
                .from_reader(&text[start..end]);
            // A row per line at most: sized once instead of grown by copies.
            let mut rays = Vec::new();
            let failed = read_rows(&mut csv, &columns, start as u64, &mut rays).err();
            (rays, failed)
        })
        .collect();
    // Every piece before the first failed one was read whole, so its rays are the ones before.
    if let Some(k) = parsed.iter().position(|(_, failed)| failed.is_some()) {
        let before: usize = parsed[..k].iter().map(|(rays, _)| rays.len()).sum();
        if let (_, Some(mut e)) = parsed.swap_remove(k) {
            e.ray += before;
            return Err(e.into_error(text, label));
        }
    }
    let mut rays = Vec::with_capacity(parsed.iter().map(|(rays, _)| rays.len()).sum());
    for (part, _) in parsed {
        rays.extend(part);
    }
    Ok(rays)
}

/// The body of `text` (from byte `body`) cut at line ends into pieces of at least `piece` bytes,
/// one or more per thread, as byte ranges; `None` when the text cannot be cut (see
/// [`parse_rays`]).
fn pieces(text: &[u8], body: usize, piece: usize) -> Option<Vec<(usize, usize)>> {
    if body >= text.len() || text.len() - body < 2 * piece || text.contains(&b'"') {
        return None;
    }
    let wanted = (rayon::current_num_threads() * 4).max(1);
    let size = ((text.len() - body) / wanted).max(piece);
    let mut cuts = vec![body];
    while let Some(&last) = cuts.last().filter(|&&c| c < text.len()) {
        let from = (last + size).min(text.len());
        let next = text[from..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(text.len(), |i| from + i + 1);
        cuts.push(next);
    }
    Some(cuts.windows(2).map(|w| (w[0], w[1])).collect())
}

/// Reads the rows of `csv`, whose text starts at byte `offset` of the file, into `rays`. A
/// flexible reader's rows are held to the header's field count here, with the message the strict
/// reader gives.
fn read_rows<R: Read>(
    csv: &mut csv::Reader<R>,
    columns: &Columns,
    offset: u64,
    rays: &mut Vec<Ray>,
) -> Result<(), RowError> {
    let mut bytes = csv::ByteRecord::new();
    let fail = |at: Option<u64>, ray: usize, of_ray: bool, reason: String| RowError {
        at: at.map(|b| b + offset),
        ray,
        of_ray,
        reason,
    };
    loop {
        match csv.read_byte_record(&mut bytes) {
            Ok(false) => return Ok(()),
            Ok(true) => {}
            Err(e) => {
                let at = e.position().map(|p| p.byte());
                return Err(fail(at, rays.len(), false, csv_reason(&e)));
            }
        }
        let at = bytes.position().map(|p| p.byte());
        if bytes.len() != columns.fields {
            let reason = format!(
                "has {}, but the header has {}",
                super::words::count(bytes.len(), "field"),
                columns.fields
            );
            return Err(fail(at, rays.len(), false, reason));
        }
        let record = csv::StringRecord::from_byte_record(bytes)
            .map_err(|_| fail(at, rays.len(), false, "not valid UTF-8".to_string()))?;
        let ray = ray_of(&record, columns).map_err(|reason| fail(at, rays.len(), true, reason))?;
        rays.push(ray);
        bytes = record.into_byte_record();
    }
}

/// The ray of one row, or what is wrong with it.
fn ray_of(record: &csv::StringRecord, columns: &Columns) -> Result<Ray, String> {
    // `finite`: the column must hold a finite number, so a finite one past f32's range (read
    // as infinity, which the ray would refuse as if the file had written one) is named as such.
    let field = |i: usize, name: &str, finite: bool| -> Result<Option<f32>, String> {
        let text = record.get(i).unwrap_or("").trim();
        if text.is_empty() {
            return Ok(None);
        }
        // Echoed escaped and cut short: a quoted cell may hold newlines or a whole file. Only
        // made for an error: building it for every cell took a quarter of a million-ray trace.
        let shown = || {
            let cut: String = text.chars().take(40).collect();
            let more = if text.chars().count() > 40 { "..." } else { "" };
            format!("{}{more}", cut.escape_debug())
        };
        let value = text
            .parse::<f32>()
            .map_err(|_| format!("column '{name}': cannot parse '{}' as a number", shown()))?;
        if finite && value.is_infinite() && !text.to_ascii_lowercase().contains("inf") {
            return Err(format!(
                "column '{name}': {} is beyond single precision's range (about 3.4e38)",
                shown()
            ));
        }
        Ok(Some(value))
    };
    let mut v = [0.0f32; 6];
    for ((value, &i), name) in v.iter_mut().zip(&columns.required).zip(REQUIRED_COLUMNS) {
        *value = field(i, name, true)?.ok_or_else(|| format!("column '{name}' is empty"))?;
    }
    // An empty tmin/tmax cell means the default, like a missing column.
    let t_min = match columns.tmin {
        Some(i) => field(i, "tmin", false)?.unwrap_or(0.0),
        None => 0.0,
    };
    let t_max = match columns.tmax {
        Some(i) => field(i, "tmax", false)?.unwrap_or(f32::INFINITY),
        None => f32::INFINITY,
    };
    let origin = Vec3::new(v[0], v[1], v[2]);
    let dir = Vec3::new(v[3], v[4], v[5]);
    Ray::segment(origin, dir, t_min, t_max).map_err(|e| e.to_string())
}

/// A CSV error without the crate's own position prefix (ours names the line).
fn csv_reason(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!(
            "has {}, but the header has {expected_len}",
            super::words::count(usize::try_from(*len).unwrap_or(usize::MAX), "field")
        ),
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
    fn written_rays_read_back_bit_for_bit() {
        let rays = [
            Ray::segment(
                Vec3::new(0.1, -0.0, 1e-7),
                Vec3::new(1.0 / 3.0, 2.0, -5.5),
                0.0,
                1.0 - 1e-4,
            )
            .unwrap(),
            Ray::new(Vec3::new(-1e30, 7.25, 3.0), Vec3::new(0.0, 0.0, -1.0)).unwrap(),
        ];
        let mut text = Vec::new();
        write_rays(&mut text, &rays).unwrap();
        let back = parse(std::str::from_utf8(&text).unwrap()).unwrap();
        assert_eq!(back.len(), 2);
        for (a, b) in rays.iter().zip(&back) {
            assert_eq!(a, b);
            assert_eq!(a.origin.x.to_bits(), b.origin.x.to_bits());
            assert_eq!(a.origin.y.to_bits(), b.origin.y.to_bits());
        }
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
    fn segment_ends_past_f32_range_read_as_infinite() {
        // Unlike an origin or a direction, a segment end may be infinite: past f32's range it
        // is, as far as the ray goes anyway.
        let rays = parse("ox,oy,oz,dx,dy,dz,tmin,tmax\n0,0,0,1,0,0,0,1e39\n").unwrap();
        assert_eq!(rays[0].t_max, f32::INFINITY);
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
            (
                "1e39,0,0,1,0,0,0,1\n",
                "column 'ox': 1e39 is beyond single precision's range",
            ),
            ("0,0,0,-4e38,0,0,0,1\n", "column 'dx': -4e38 is beyond"),
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

    /// Lines are counted by their ends, LF, CRLF or lone CR: the CSV reader's own count lost one
    /// per CRLF, and a header after blank lines is not on line 1.
    #[test]
    fn lines_are_counted_with_crlf_and_blank_lines() {
        assert_eq!(
            line_of("ox,oy,oz,dx,dy,dz\r\n1,2,3,0,0,1\r\n0,0,0,0,0,0\r\n"),
            Some(3)
        );
        assert_eq!(
            line_of("ox,oy,oz,dx,dy,dz\r\n\r\n1,2,3,0,0,1\r\n\n\r\n0,0,0,1,0\r\n"),
            Some(6)
        );
        assert_eq!(line_of("\n\r\nox,oy,oz,dx,dy\n0,0,0,1,0\n"), Some(3));
        assert_eq!(
            line_of("ox,oy,oz,dx,dy,dz\r1,2,3,0,0,1\r\r\n0,0,0,0,0,0\r"),
            Some(4)
        );
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

    /// Reading in pieces on every thread gives the rays, the error, its line and its ray index
    /// that reading on one thread gives, over random files of good and bad rows, blank lines,
    /// CRLF and lone CR line ends, quotes, bad UTF-8, a BOM and blank lines before the header.
    #[test]
    fn pieces_read_as_one_thread_reads() {
        let rows: [&[u8]; 16] = [
            b"1,2,3,0,0,1",
            b" 1 , 2,\t3,0,1,0",
            b"-0,1e-3,5,1,1,1",
            b"0.5,0.25,0,0,-1,0",
            b"",
            b"",
            b"0,0,0,0,0,0",
            b"0,0,0,1,x,0",
            b"0,0,0,1,0",
            b"0,0,0,1,0,0,7,8,9",
            b"0,0,,1,0,0",
            b"nan,0,0,1,0,0",
            b"0,\xff,0,1,0,0",
            b"0,\"1\",0,1,0,0",
            b"inf,0,0,1,0,0",
            b"2,2,2,0,0,3",
        ];
        let heads: [&[u8]; 4] = [
            b"ox,oy,oz,dx,dy,dz",
            b"\nox,oy,oz,dx,dy,dz",
            b"\xef\xbb\xbfdz,dy,dx,oz,oy,ox",
            b"ox,oy,oz,dx,dy,dz,tmin,tmax",
        ];
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: usize| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng % n as u64) as usize
        };
        let mut in_pieces = 0;
        for _ in 0..3000 {
            let head = heads[next(heads.len())];
            let mut text = head.to_vec();
            // Mostly good rows, so some files get far before their first error.
            let bad_rate = [0, 2, 40][next(3)];
            for _ in 0..next(60) {
                text.extend_from_slice(match next(5) {
                    0 => b"\r\n".as_slice(),
                    1 if next(20) == 0 => b"\r",
                    _ => b"\n",
                });
                let row = if next(100) < bad_rate {
                    rows[next(rows.len())]
                } else {
                    rows[next(6)]
                };
                let row = if head.ends_with(b"tmax") && !row.is_empty() {
                    [row, b",0,5"].concat()
                } else {
                    row.to_vec()
                };
                text.extend_from_slice(&row);
            }
            if next(2) == 0 {
                text.push(b'\n');
            }
            let label = Path::new("rays.csv");
            let one = parse_text(&text, label, usize::MAX / 4);
            let cut = parse_text(&text, label, 8);
            match (&one, &cut) {
                (Ok(a), Ok(b)) => assert_eq!(a, b),
                (Err(a), Err(b)) => assert_eq!(
                    (a.line, a.to_string()),
                    (b.line, b.to_string()),
                    "{}",
                    String::from_utf8_lossy(&text).escape_debug()
                ),
                _ => panic!(
                    "{one:?} vs {cut:?} for {}",
                    String::from_utf8_lossy(&text).escape_debug()
                ),
            }
            let mut csv = csv::Reader::from_reader(text.as_slice());
            if csv.headers().is_ok() {
                let body = csv.position().byte() as usize;
                in_pieces += usize::from(pieces(&text, body, 8).is_some_and(|p| p.len() > 1));
            }
        }
        assert!(in_pieces > 1000, "{in_pieces} read in pieces");
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
