//! `rdbvh trace`: answer a batch of ray queries from a CSV file, in parallel, in input order,
//! with one BVH over the scene or (with `--areas`) through the scene structure of influence
//! areas, local BVHs and a fallback BVH.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{value_parser, Args, ValueEnum};
use rayon::prelude::*;
use rdbvh_core::bvh::{Hit, Traversable, WideBvh};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::toplevel::MAX_OCTREE_LEVELS;

use super::builder::BuilderArgs;
use super::rays::read_rays;
use super::{load_scene, structure, CliError};

/// How the scene structure finds the areas that may contain a ray's origin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LookupKind {
    /// An octree over the areas: constant time per query.
    Octree,
    /// Every area is a candidate: the naive baseline.
    List,
}

/// Arguments of `rdbvh trace`.
#[derive(Args, Clone, Debug)]
pub struct TraceArgs {
    /// The scene: an OBJ file, or builtin:NAME for a built-in scene.
    #[arg(value_name = "SCENE.obj")]
    pub scene: String,
    /// Rays, one per row: header `ox,oy,oz,dx,dy,dz`, optionally `tmin,tmax` (any order).
    #[arg(long, value_name = "RAYS.csv")]
    pub rays: PathBuf,
    /// Where to write the answers: `ray,t,triangle,u,v` (closest hit, empty on a miss) or
    /// `ray,hit` (with --any-hit).
    #[arg(long, value_name = "HITS.csv")]
    pub out: PathBuf,
    /// Answer "is anything hit on [tmin, tmax]" (shadow rays) instead of the closest hit.
    #[arg(long)]
    pub any_hit: bool,
    /// How to build the BVH (with --areas: the local BVHs, which need --preset; the fallback
    /// BVH is always binned SAH with default settings).
    #[command(flatten)]
    pub builder: BuilderArgs,
    /// Influence areas (TOML): answer through the scene structure, with a local BVH over the
    /// triangles of each area that applies to the scene and a fallback BVH for other rays.
    #[arg(long, value_name = "AREAS.toml")]
    pub areas: Option<PathBuf>,
    /// With --areas: how a ray's origin finds its candidate areas.
    #[arg(long, value_enum, default_value_t = LookupKind::Octree, requires = "areas")]
    pub lookup: LookupKind,
    /// With --areas and the octree lookup: its maximum number of levels [default: 5]
    #[arg(long, value_name = "N", requires = "areas",
          value_parser = value_parser!(u32).range(1..=i64::from(MAX_OCTREE_LEVELS)))]
    pub octree_levels: Option<u32>,
    /// With --areas: how many affine areas a ray tries before the fallback BVH.
    #[arg(long, value_name = "K", default_value_t = 1, requires = "areas",
          value_parser = value_parser!(u32).range(1..))]
    pub max_tries: u32,
}

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

    /// Writes the answers as CSV. Floats use Rust's shortest round-trip formatting, so reading
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

/// Traces every ray in parallel through `tree` (binary or 4-wide); the answers keep the rays'
/// order.
pub fn trace<T: Traversable + Sync>(
    tree: &T,
    triangles: &[Triangle],
    rays: &[Ray],
    any_hit: bool,
) -> Answers {
    if any_hit {
        Answers::Any(
            rays.par_iter()
                .map(|r| tree.any_hit(r, triangles))
                .collect(),
        )
    } else {
        Answers::Closest(
            rays.par_iter()
                .map(|r| tree.closest_hit(r, triangles))
                .collect(),
        )
    }
}

/// Runs `rdbvh trace`; the summary goes to `log` (standard error), so standard output stays free.
pub fn run(args: &TraceArgs, log: &mut impl Write) -> Result<(), CliError> {
    let inputs = [Path::new(&args.scene), args.rays.as_path()];
    let areas = args.areas.as_deref().into_iter();
    super::check_output(
        &args.out,
        &inputs.into_iter().chain(areas).collect::<Vec<_>>(),
    )?;
    if let Some(areas) = &args.areas {
        return structure::run(args, areas, log);
    }
    args.builder.check_area(false)?;
    let (scene, _) = load_scene(&args.scene, Some(&args.out))?;
    let rays = read_rays(&args.rays)?;
    // Queries run on the 4-wide collapse of the built tree: the same answers, faster.
    let built = args.builder.build_for_wide(&scene.triangles)?;
    let wide = WideBvh::from_binary(&built.bvh, &scene.triangles);

    let start = Instant::now();
    let answers = trace(&wide, &scene.triangles, &rays, args.any_hit);
    let seconds = start.elapsed().as_secs_f64();

    write_answers(&args.out, &answers)?;
    let kind = if args.any_hit {
        "any hit"
    } else {
        "closest hit"
    };
    let per_second = if rays.is_empty() {
        0.0
    } else {
        rays.len() as f64 / seconds.max(1e-9)
    };
    writeln!(
        log,
        "traced {} ({kind}) against {} with {}: {}, {:.3} ms, {:.0} rays/s",
        super::count(rays.len(), "ray"),
        super::count(scene.len(), "triangle"),
        super::count(rayon::current_num_threads(), "thread"),
        super::count(answers.hits(), "hit"),
        seconds * 1e3,
        per_second
    )
    .map_err(CliError::Stdout)
}

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
    use rdbvh_core::Vec3;

    #[test]
    fn the_octree_levels_help_says_the_default() {
        // `--octree-levels` is an Option (so `--lookup list` can refuse it), so clap cannot show
        // its default: the help spells it out, and must say the one the code uses.
        use clap::CommandFactory;
        let cli = super::super::Cli::command();
        let trace = cli.find_subcommand("trace").unwrap();
        let arg = trace
            .get_arguments()
            .find(|a| a.get_id() == "octree_levels")
            .unwrap();
        let help = arg.get_help().unwrap().to_string();
        let default = rdbvh_core::toplevel::DEFAULT_OCTREE_LEVELS;
        assert!(help.contains(&format!("[default: {default}]")), "{help}");
    }

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

    #[test]
    fn parallel_trace_keeps_order_and_agrees_with_brute_force() {
        let tris: Vec<Triangle> = (0..50)
            .map(|i| {
                let o = Vec3::new(i as f32, 0.0, 1.0 + (i % 5) as f32);
                Triangle::new(o, o + Vec3::X, o + Vec3::Y)
            })
            .collect();
        let bvh = BuilderArgs::default().build(&tris).unwrap().bvh;
        let rays: Vec<Ray> = (0..500)
            .map(|i| {
                let o = Vec3::new(i as f32 * 0.1, 0.3, 0.0);
                Ray::new(o, Vec3::new(0.01, 0.0, 1.0)).unwrap()
            })
            .collect();
        let wide = WideBvh::from_binary(&bvh, &tris);
        let binary = (
            trace(&bvh, &tris, &rays, false),
            trace(&bvh, &tris, &rays, true),
        );
        let four = (
            trace(&wide, &tris, &rays, false),
            trace(&wide, &tris, &rays, true),
        );
        for (closest, any) in [binary, four] {
            let (Answers::Closest(closest), Answers::Any(any)) = (closest, any) else {
                unreachable!()
            };
            for (i, r) in rays.iter().enumerate() {
                assert_eq!(closest[i], rdbvh_core::brute_force::closest_hit(r, &tris));
                assert_eq!(any[i], rdbvh_core::brute_force::any_hit(r, &tris));
            }
            assert!(closest.iter().any(Option::is_some) && closest.iter().any(Option::is_none));
        }
    }
}
