//! One frame: tiles on rayon's threads, the frame's counters, the shadow rays kept for the
//! replay, and the recorded rays.
//!
//! Tiles are 16 x 16 pixels in row-major order. A batch of consecutive tiles is one task: its
//! paths are traced, then their shadow segments answered together ([`PathBatch`]), then their
//! radiance summed. Batches run in groups of a few per thread, and each group's output is
//! appended in tile order, so everything a frame keeps (the shadow rays for the replay, the
//! recorded rays) is the same for a seed whatever the thread count: the first rays in tile
//! order, then pixel order within the tile (row-major), then sample, then path vertex.

use std::cell::RefCell;
use std::ops::Range;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use rdbvh_core::bvh::Hit;
use rdbvh_core::geometry::Ray;
use rdbvh_core::Vec3;

use super::integrator::{Integrator, PathObserver, ShadowRay};
use super::sampler::{Sampler, DIM_PIXEL_X, DIM_PIXEL_Y};
use super::shadow_batch::{PathBatch, ShadowTests};
use super::Camera;

/// Tile side in pixels.
pub const TILE: u32 = 16;

/// At most this many of the frame's shadow rays are kept for the replay (about 150 MB); a frame
/// with more replays its first ones.
pub const REPLAY_CAP: usize = 1 << 21;

/// Samples a batch of tiles holds, at least: enough shadow segments (a few per sample) that
/// those of one light buffer cell come in runs, few enough that a batch's paths stay in memory
/// (a few MB).
pub const BATCH_SAMPLES: usize = 1 << 15;

/// Batches per thread in one group: enough to balance the threads, few enough that a group's
/// kept rays stay small. A frame has at least this many batches per thread where it has the
/// tiles, however few samples they hold. A frame traced one tile a task (no batches) puts as many
/// tiles in a group as a batched frame does, so that both wait for a group's last task and merge
/// a group's output equally often: in groups of this many single tiles, the global BVH's Sponza
/// frame kept its threads busy 91-92 % of the time, against 95 % in groups of as many tiles.
const BATCHES_PER_THREAD: usize = 4;

thread_local! {
    /// Each thread's batch of paths, kept from frame to frame: a batch holds a few MB, which
    /// allocated afresh for each batch cost page faults and copies as it grew.
    static PATHS: RefCell<PathBatch> = RefCell::new(PathBatch::default());
}

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// The seed of every random number.
    pub seed: u64,
    /// How many rays of each kind to record (0: none).
    pub record_limit: usize,
    /// Whether to show a progress bar on standard error.
    pub progress: bool,
}

/// The frame's ray counts and shadow-ray test counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameCounters {
    /// Camera rays traced.
    pub camera_rays: u64,
    /// Bounce rays traced.
    pub bounce_rays: u64,
    /// Shadow segments traced.
    pub shadow_rays: u64,
    /// Shadow segments that something blocked.
    pub shadow_occluded: u64,
    /// Inner nodes the shadow segments visited (a light buffer's cell lookup counts as one).
    pub shadow_node_tests: u64,
    /// Ray/triangle tests of the shadow segments.
    pub shadow_triangle_tests: u64,
}

impl FrameCounters {
    fn add(&mut self, o: &FrameCounters) {
        self.camera_rays += o.camera_rays;
        self.bounce_rays += o.bounce_rays;
        self.shadow_rays += o.shadow_rays;
        self.shadow_occluded += o.shadow_occluded;
        self.shadow_node_tests += o.shadow_node_tests;
        self.shadow_triangle_tests += o.shadow_triangle_tests;
    }
}

/// The first rays of each kind with the renderer's answers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordedRays {
    /// Camera rays and their closest hits.
    pub camera: Vec<(Ray, Option<Hit>)>,
    /// Bounce rays and their closest hits.
    pub bounce: Vec<(Ray, Option<Hit>)>,
    /// Shadow segments and their answers.
    pub shadow: Vec<ShadowRay>,
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Linear radiance per pixel, row-major from the top left, averaged over the samples.
    pub pixels: Vec<Vec3>,
    /// The frame's counts.
    pub counters: FrameCounters,
    /// The first [`REPLAY_CAP`] shadow segments, for the replay.
    pub shadow_rays: Vec<ShadowRay>,
    /// How many of `shadow_rays` each batch made, in order: the replay answers them in the
    /// same batches.
    pub shadow_batches: Vec<usize>,
    /// The recorded rays (empty without a record limit).
    pub recorded: RecordedRays,
    /// Wall-clock milliseconds of the frame.
    pub render_ms: f64,
}

/// What one batch of tiles gives back.
struct BatchOutput {
    /// Each pixel's index and radiance, tile by tile, row by row.
    pixels: Vec<(usize, Vec3)>,
    observer: Observer,
}

/// Counts a tile's rays and keeps its first ones, up to the room the frame has left.
struct Observer {
    counters: FrameCounters,
    shadow: Vec<ShadowRay>,
    shadow_room: usize,
    recorded: RecordedRays,
    /// Room left for camera, bounce and shadow rays.
    record_room: [usize; 3],
}

impl PathObserver for Observer {
    #[inline]
    fn closest(&mut self, depth: u32, ray: &Ray, hit: Option<&Hit>) {
        let (count, kept, room) = if depth == 0 {
            let r = &mut self.recorded.camera;
            (&mut self.counters.camera_rays, r, self.record_room[0])
        } else {
            let r = &mut self.recorded.bounce;
            (&mut self.counters.bounce_rays, r, self.record_room[1])
        };
        *count += 1;
        if kept.len() < room {
            kept.push((*ray, hit.copied()));
        }
    }

    #[inline]
    fn shadow(&mut self, shadow: &ShadowRay) {
        self.shadows(std::slice::from_ref(shadow));
    }

    #[inline]
    fn shadows(&mut self, shadows: &[ShadowRay]) {
        let c = &mut self.counters;
        c.shadow_rays += shadows.len() as u64;
        c.shadow_occluded += shadows.iter().filter(|s| s.occluded).count() as u64;
        for (kept, room) in [
            (&mut self.shadow, self.shadow_room),
            (&mut self.recorded.shadow, self.record_room[2]),
        ] {
            let n = room.saturating_sub(kept.len()).min(shadows.len());
            kept.extend_from_slice(&shadows[..n]);
        }
    }

    #[inline]
    fn shadow_tests(&mut self, tests: &ShadowTests) {
        self.counters.shadow_node_tests += tests.nodes;
        self.counters.shadow_triangle_tests += tests.triangles;
    }
}

/// Renders a frame on the current rayon pool.
pub fn render_frame(integrator: &Integrator, camera: &Camera, settings: &FrameSettings) -> Frame {
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    let (tiles_x, tiles_y) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let tiles = (tiles_x * tiles_y) as usize;
    let progress = if settings.progress {
        ProgressBar::new(tiles as u64).with_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} tiles {elapsed} (eta {eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        )
    } else {
        ProgressBar::hidden()
    };
    let mut frame = Frame {
        pixels: vec![Vec3::ZERO; (w as usize) * (h as usize)],
        counters: FrameCounters::default(),
        shadow_rays: Vec::new(),
        shadow_batches: Vec::new(),
        recorded: RecordedRays::default(),
        render_ms: 0.0,
    };
    let threads = rayon::current_num_threads().max(1);
    let samples_per_tile = (TILE * TILE) as usize * settings.spp.max(1) as usize;
    let tiles_per_batch = BATCH_SAMPLES
        .div_ceil(samples_per_tile)
        .min(tiles / (threads * BATCHES_PER_THREAD))
        .max(1);
    // A structure that answers each shadow segment where it is made needs no batch but a tile;
    // its groups span as many tiles as the batched ones (see `BATCHES_PER_THREAD`).
    let per_batch = if integrator.batched() {
        tiles_per_batch
    } else {
        1
    };
    let batches = tiles.div_ceil(per_batch);
    let group = threads * BATCHES_PER_THREAD * tiles_per_batch / per_batch;
    for first in (0..batches).step_by(group) {
        let room = |kept: usize, cap: usize| cap.saturating_sub(kept);
        let shadow_room = room(frame.shadow_rays.len(), REPLAY_CAP);
        let r = &frame.recorded;
        let record_room = [r.camera.len(), r.bounce.len(), r.shadow.len()]
            .map(|kept| room(kept, settings.record_limit));
        let outputs: Vec<BatchOutput> = (first..batches.min(first + group))
            .into_par_iter()
            .map(|b| {
                let tiles = b * per_batch..tiles.min((b + 1) * per_batch);
                let n = tiles.len() as u64;
                let out = PATHS.with_borrow_mut(|paths| {
                    render_tiles(
                        integrator,
                        camera,
                        settings,
                        (tiles, tiles_x),
                        paths,
                        shadow_room,
                        record_room,
                    )
                });
                progress.inc(n);
                out
            })
            .collect();
        for out in outputs {
            for (i, p) in out.pixels {
                frame.pixels[i] = p;
            }
            let o = out.observer;
            frame.counters.add(&o.counters);
            let kept = frame.shadow_rays.len();
            keep(&mut frame.shadow_rays, o.shadow, REPLAY_CAP);
            if frame.shadow_rays.len() > kept {
                frame.shadow_batches.push(frame.shadow_rays.len() - kept);
            }
            let limit = settings.record_limit;
            keep(&mut frame.recorded.camera, o.recorded.camera, limit);
            keep(&mut frame.recorded.bounce, o.recorded.bounce, limit);
            keep(&mut frame.recorded.shadow, o.recorded.shadow, limit);
        }
    }
    progress.finish_and_clear();
    frame.render_ms = start.elapsed().as_secs_f64() * 1e3;
    frame
}

/// Appends `more` to `kept` up to `cap` items in all.
fn keep<T>(kept: &mut Vec<T>, more: Vec<T>, cap: usize) {
    let room = cap.saturating_sub(kept.len());
    kept.extend(more.into_iter().take(room));
}

/// Renders the tiles `tiles` of a frame `tiles_x` tiles wide as one batch of paths in `paths`,
/// keeping up to `shadow_room` shadow rays and `record_room` rays of each kind.
fn render_tiles(
    integrator: &Integrator,
    camera: &Camera,
    s: &FrameSettings,
    (tiles, tiles_x): (Range<usize>, u32),
    paths: &mut PathBatch,
    shadow_room: usize,
    record_room: [usize; 3],
) -> BatchOutput {
    let mut observer = Observer {
        counters: FrameCounters::default(),
        shadow: Vec::new(),
        shadow_room,
        recorded: RecordedRays::default(),
        record_room,
    };
    paths.clear();
    let batched = integrator.batched();
    let mut pixels = Vec::with_capacity(tiles.len() * (TILE * TILE) as usize);
    for tile in tiles {
        let (tx, ty) = (tile as u32 % tiles_x, tile as u32 / tiles_x);
        for y in ty * TILE..((ty + 1) * TILE).min(s.height) {
            for x in tx * TILE..((tx + 1) * TILE).min(s.width) {
                let pixel = u64::from(y) * u64::from(s.width) + u64::from(x);
                let mut sum = Vec3::ZERO;
                for sample in 0..s.spp {
                    let sampler = Sampler::new(s.seed, pixel, sample);
                    let ray = camera.ray(
                        x as f32 + sampler.get(DIM_PIXEL_X),
                        y as f32 + sampler.get(DIM_PIXEL_Y),
                    );
                    if batched {
                        integrator.trace(ray, &sampler, &mut observer, paths);
                    } else {
                        sum += integrator.radiance(ray, &sampler, &mut observer);
                    }
                }
                pixels.push((pixel as usize, sum / s.spp as f32));
            }
        }
    }
    if !batched {
        return BatchOutput { pixels, observer };
    }
    integrator.answer(paths);
    observer.shadows(&paths.segments);
    observer.shadow_tests(&paths.tests);
    // Each pixel's samples, summed in order as the paths were traced.
    let mut radiance = paths.radiance();
    for (_, p) in &mut pixels {
        let mut sum = Vec3::ZERO;
        for r in radiance.by_ref().take(s.spp as usize) {
            sum += r;
        }
        *p = sum / s.spp as f32;
    }
    BatchOutput { pixels, observer }
}
