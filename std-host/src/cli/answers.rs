//! The answers of a batch of rays and their CSV: what `rdbvh trace --out` writes and
//! `rdbvh render --record-rays` writes beside its rays.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use rayon::prelude::*;
use rdbvh_core::bvh::Hit;

use super::error::CliError;

/// The answers of one batch, in ray order.
#[derive(Clone, Debug, PartialEq)]
pub enum Answers {
    /// Closest hit per ray.
    Closest(Vec<Option<Hit>>),
    /// Any hit per ray.
    Any(Vec<bool>),
}

impl Answers {
    /// How many rays hit something.
    pub fn hits(&self) -> usize {
        match self {
            Answers::Closest(h) => h.iter().filter(|h| h.is_some()).count(),
            Answers::Any(h) => h.iter().filter(|&&h| h).count(),
        }
    }

    /// Writes the answers as CSV. Floats use the shortest formatting that reads back exactly, so reading
    /// them back as `f32` gives the same bits, except that a negative zero (a barycentric on an
    /// edge, rounded from the wrong side) is written `0`, not `-0`.
    pub fn write_csv(&self, out: &mut impl Write) -> std::io::Result<()> {
        match self {
            Answers::Closest(hits) => {
                writeln!(out, "ray,t,triangle,u,v")?;
                // Shortest float formatting is most of writing a large batch: rows are formatted
                // in chunks on every thread, a bounded group at a time, and written in order.
                let group = WRITE_CHUNK * rayon::current_num_threads().max(1);
                for (g, rows) in hits.chunks(group).enumerate() {
                    let texts = rows
                        .par_chunks(WRITE_CHUNK)
                        .enumerate()
                        .map(|(c, chunk)| {
                            let first = g * group + c * WRITE_CHUNK;
                            let mut text = Vec::with_capacity(chunk.len() * 40);
                            for (i, hit) in (first..).zip(chunk) {
                                match hit {
                                    Some(h) => {
                                        // `x + 0.0` is `x` for every float but -0, which becomes +0.
                                        let (t, u, v) = (h.t + 0.0, h.u + 0.0, h.v + 0.0);
                                        writeln!(text, "{i},{t},{},{u},{v}", h.triangle)?
                                    }
                                    None => writeln!(text, "{i},,,,")?,
                                }
                            }
                            Ok(text)
                        })
                        .collect::<std::io::Result<Vec<Vec<u8>>>>()?;
                    for text in texts {
                        out.write_all(&text)?;
                    }
                }
            }
            Answers::Any(hits) => {
                writeln!(out, "ray,hit")?;
                for (i, &hit) in hits.iter().enumerate() {
                    writeln!(out, "{i},{}", u8::from(hit))?;
                }
            }
        }
        Ok(())
    }
}

/// Rows of closest-hit answers formatted by one task of [`Answers::write_csv`].
const WRITE_CHUNK: usize = 1 << 15;

/// Writes `answers` to the CSV file at `path`.
pub(super) fn write_answers(path: &Path, answers: &Answers) -> Result<(), CliError> {
    let error = |source| CliError::Write {
        path: path.to_path_buf(),
        source,
    };
    let mut out = BufWriter::new(File::create(path).map_err(error)?);
    answers.write_csv(&mut out).map_err(error)?;
    out.flush().map_err(error)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_layout() {
        let hit = Hit {
            t: 0.1,
            triangle: 3,
            u: 0.25,
            v: 1e-8,
        };
        let mut out = Vec::new();
        Answers::Closest(vec![Some(hit), None])
            .write_csv(&mut out)
            .unwrap();
        let text = String::from_utf8(out).unwrap();
        assert_eq!(text, "ray,t,triangle,u,v\n0,0.1,3,0.25,0.00000001\n1,,,,\n");
        let line = text.lines().nth(1).unwrap();
        let v: f32 = line.rsplit(',').next().unwrap().parse().unwrap();
        assert_eq!(v, 1e-8);
        // A barycentric rounded to -0 on an edge is written 0.
        let edge = Hit { u: -0.0, ..hit };
        let mut out = Vec::new();
        Answers::Closest(vec![Some(edge)])
            .write_csv(&mut out)
            .unwrap();
        assert!(String::from_utf8(out)
            .unwrap()
            .ends_with("\n0,0.1,3,0,0.00000001\n"));

        let mut out = Vec::new();
        Answers::Any(vec![false, true]).write_csv(&mut out).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), "ray,hit\n0,0\n1,1\n");
    }

    #[test]
    fn answers_past_one_chunk_keep_their_rows_in_order() {
        // More rows than one group of chunks: each row names its ray, in order.
        let n = 3 * WRITE_CHUNK * rayon::current_num_threads().max(1) + 17;
        let hits = (0..n)
            .map(|i| {
                (i % 3 != 0).then_some(Hit {
                    t: i as f32,
                    triangle: i as u32,
                    u: 0.5,
                    v: 0.25,
                })
            })
            .collect();
        let mut out = Vec::new();
        Answers::Closest(hits).write_csv(&mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(rows.len(), n);
        for (i, row) in rows.iter().enumerate() {
            let expect = if i % 3 == 0 {
                format!("{i},,,,")
            } else {
                format!("{i},{},{i},0.5,0.25", i as f32)
            };
            assert_eq!(*row, expect);
        }
    }
}
