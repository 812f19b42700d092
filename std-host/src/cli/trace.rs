//! `rdbvh trace`: answer a batch of ray queries from a CSV file, in parallel, in input order,
//! with one BVH over the scene or (with `--areas`) through the scene structure of influence
//! areas, local BVHs and a fallback BVH.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{value_parser, Args, ValueEnum};
use rayon::prelude::*;
use rdbvh_core::bvh::{Traversable, WideBvh};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::toplevel::MAX_OCTREE_LEVELS;

use super::answers::{write_answers, Answers};
use super::builder::BuilderArgs;
use super::error::CliError;
use super::inputs::load_scene;
use super::rays::read_rays;

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
    /// Rays, one per row: header `ox,oy,oz,dx,dy,dz`, optionally `tmin,tmax` (any order; other
    /// columns are not read, with a warning).
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

/// Fails before any work when `--out` cannot be written or is one of the command's inputs.
pub(super) fn check_outputs(args: &TraceArgs) -> Result<(), CliError> {
    let inputs = [Path::new(&args.scene), args.rays.as_path()];
    let areas = args.areas.as_deref().into_iter();
    super::inputs::check_output(
        &args.out,
        &inputs.into_iter().chain(areas).collect::<Vec<_>>(),
    )
}

/// Runs `rdbvh trace` without `--areas` (with them, [`super::structure::run`] does): one BVH over
/// the scene, traced as its 4-wide collapse. The summary goes to `log` (standard error), so
/// standard output stays free.
pub fn run(args: &TraceArgs, log: &mut impl Write) -> Result<(), CliError> {
    check_outputs(args)?;
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
        super::words::count(rays.len(), "ray"),
        super::words::count(scene.len(), "triangle"),
        super::words::count(rayon::current_num_threads(), "thread"),
        super::words::count(answers.hits(), "hit"),
        seconds * 1e3,
        per_second
    )
    .map_err(CliError::Stdout)
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
