//! The acceleration structure the integrator traces through, chosen with `--structure`.
//!
//! Bounce rays always go through the global BVH. Shadow rays go through the structure: with
//! `global` the same BVH, with `lights` the light buffer of the ray's light when it has one, and
//! the global BVH for every segment the buffer does not answer, with `thesis` the thesis's
//! influence areas, octree and fallback ([`super::ThesisStructure`]). Camera rays go through
//! `lights`'s eye buffer when it kept one ([`super::eye_buffer`]), through the global BVH
//! otherwise. All answer every query exactly as the global BVH does, so the images are
//! byte-identical. `lights` answers a batch of
//! segments fastest cell by cell of its buffers ([`Structure::occluded_batch`]).

use std::time::Instant;

use rdbvh_core::builder::{parallel, BuildOptions, Preset};
use rdbvh_core::bvh::{Hit, TraversalStats, WideBvh8};
use rdbvh_core::geometry::{Ray, Triangle, TriangleEdges};
use rdbvh_core::light_buffer::LightBuffer;
use rdbvh_core::prefetch_all;

use super::light_structure::light_buffers;
use super::shadow_batch::{BatchOrder, ShadowTests, NO_CELL};
use super::thesis::ThesisStructure;
use super::{Light, RenderError, ShadowRay};

/// Which structure answers the shadow rays (`--structure`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StructureKind {
    /// The global BVH: binned SAH with reinsertion (Bittner et al. 2013), collapsed to 8-wide
    /// nodes, the fastest single BVH rdbvh builds for these rays.
    Global,
    /// A light buffer per light (per cluster of emissive triangles), built from the lights
    /// automatically and kept where a pilot frame's shadow rays show that it pays
    /// ([`super::pilot`]), with the global BVH for what a buffer does not answer; and for the
    /// camera rays the buffer of a spot light at the eye, its cone the view, where the pilot's
    /// camera rays show that it pays ([`super::eye_buffer`]).
    Lights,
    /// The thesis's structure with influence areas made from the lights: six frustums around
    /// a point light, one along a spot, an oriented box in front of a quad light or an emissive
    /// cluster; a local BVH per area (PAH), an octree over the areas, and the global BVH as the
    /// fallback ([`super::ThesisStructure`]).
    Thesis,
}

impl StructureKind {
    /// The name `--structure` takes and reports print.
    pub fn name(self) -> &'static str {
        match self {
            StructureKind::Global => "global",
            StructureKind::Lights => "lights",
            StructureKind::Thesis => "thesis",
        }
    }
}

/// A built structure over a scene and its lights.
#[derive(Clone, Debug)]
pub struct Structure {
    kind: StructureKind,
    global: WideBvh8,
    buffers: Vec<LightBuffer>,
    /// Per light (index into the renderer's lights), its buffer's index, or `NO_BUFFER`.
    buffer_of: Vec<u32>,
    /// `lights`: a light buffer at the camera's eye, for the camera rays, when the pilot frame
    /// showed that it pays ([`super::pilot`]).
    eye: Option<LightBuffer>,
    /// The `thesis` structure, which owns the global BVH as its fallback (`global` is then
    /// empty: no second copy).
    thesis: Option<ThesisStructure>,
    build_ms: f64,
    /// The global BVH's share of `build_ms`.
    global_build_ms: f64,
}

/// How many segments ahead a batch answered out of order fetches the next one's lines.
const PREFETCH_AHEAD: usize = 4;

/// A light without a buffer of its own.
pub(super) const NO_BUFFER: u32 = u32::MAX;

impl Structure {
    /// Builds the structure `kind` over `triangles` for `lights` on the current rayon pool.
    pub fn build(
        kind: StructureKind,
        triangles: &[Triangle],
        lights: &[Light],
    ) -> Result<Self, RenderError> {
        parallel::start_pool();
        let start = Instant::now();
        let options = BuildOptions {
            reinsert: Some(Default::default()),
            parallel: true,
            ..BuildOptions::new(Preset::Sah)
        };
        let bvh = options.build(triangles, None)?;
        let mut global = WideBvh8::from_binary(&bvh, triangles);
        let global_build_ms = start.elapsed().as_secs_f64() * 1e3;
        let (buffers, buffer_of) = match kind {
            StructureKind::Global | StructureKind::Thesis => {
                (Vec::new(), vec![NO_BUFFER; lights.len()])
            }
            StructureKind::Lights => light_buffers(triangles, &global, lights)?,
        };
        let thesis = match kind {
            StructureKind::Thesis => Some(ThesisStructure::build(
                triangles,
                lights,
                std::mem::take(&mut global),
            )?),
            _ => None,
        };
        Ok(Self {
            kind,
            global,
            buffers,
            buffer_of,
            eye: None,
            thesis,
            build_ms: start.elapsed().as_secs_f64() * 1e3,
            global_build_ms,
        })
    }

    /// The kind built.
    pub fn kind(&self) -> StructureKind {
        self.kind
    }

    /// Wall-clock milliseconds of the whole build (global BVH and light buffers).
    pub fn build_ms(&self) -> f64 {
        self.build_ms
    }

    /// Wall-clock milliseconds of the global BVH's build alone: `build_ms` less this is what the
    /// light buffers (and the pilot frame) or the thesis's areas cost.
    pub fn global_build_ms(&self) -> f64 {
        self.global_build_ms
    }

    /// The light buffers built (none for `global`).
    pub fn light_buffers(&self) -> &[LightBuffer] {
        &self.buffers
    }

    /// The global BVH.
    #[inline]
    pub fn global(&self) -> &WideBvh8 {
        match &self.thesis {
            Some(t) => t.fallback(),
            None => &self.global,
        }
    }

    /// The `thesis` structure, when that is the kind built.
    pub fn thesis(&self) -> Option<&ThesisStructure> {
        self.thesis.as_ref()
    }

    /// The eye buffer of `lights`, when the pilot frame kept one ([`super::eye_buffer`]).
    pub fn eye_buffer(&self) -> Option<&LightBuffer> {
        self.eye.as_ref()
    }

    /// Makes `eye` (a light buffer at the camera's eye, see [`Structure::eye_buffer`]) answer
    /// the camera rays.
    pub(super) fn install_eye(&mut self, eye: Option<LightBuffer>) {
        self.eye = eye;
    }

    /// The index of `light`'s buffer, if it has one.
    pub fn buffer_of(&self, light: usize) -> Option<usize> {
        let b = self.buffer_of[light];
        (b != NO_BUFFER).then_some(b as usize)
    }

    /// Keeps the buffers whose `keep` entry is true (one per buffer, in order) and sends the
    /// others' lights to the global BVH.
    pub(super) fn keep_buffers(&mut self, keep: &[bool]) {
        let mut new_index = vec![NO_BUFFER; self.buffers.len()];
        let mut next = 0;
        for (b, &k) in keep.iter().enumerate() {
            if k {
                new_index[b] = next;
                next += 1;
            }
        }
        let mut keeps = keep.iter();
        self.buffers.retain(|_| keeps.next() == Some(&true));
        for slot in &mut self.buffer_of {
            if *slot != NO_BUFFER {
                *slot = new_index[*slot as usize];
            }
        }
    }

    /// Makes this structure `lights` with `buffers`, `buffer_of` naming each light's buffer
    /// (or `NO_BUFFER`), for a host that chose which buffers to build ([`super::pilot`]).
    pub(super) fn install_buffers(&mut self, buffers: Vec<LightBuffer>, buffer_of: Vec<u32>) {
        self.kind = StructureKind::Lights;
        self.buffers = buffers;
        self.buffer_of = buffer_of;
    }

    /// Sets the build time to what the whole build took, pilot frame included.
    pub(super) fn set_build_ms(&mut self, ms: f64) {
        self.build_ms = ms;
    }

    /// Adds work done after the build that belongs to it (the pilot frame) to its time.
    pub(super) fn add_build_ms(&mut self, ms: f64) {
        self.build_ms += ms;
    }

    /// The closest hit of a bounce ray, with its triangle's first vertex and edges from the leaf
    /// block that held it: always the global BVH.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<(Hit, TriangleEdges)> {
        self.global().closest_hit_edges(ray)
    }

    /// [`Structure::closest_hit`] for a camera ray: through the eye buffer's cell of the ray's
    /// direction where `lights` kept one, through the global BVH otherwise. The same answer
    /// either way, bit for bit.
    #[inline]
    pub fn closest_hit_camera(&self, ray: &Ray) -> Option<(Hit, TriangleEdges)> {
        match self
            .eye
            .as_ref()
            .and_then(|e| e.closest_hit_leaving(&self.global, ray))
        {
            Some(found) => found,
            None => self.closest_hit(ray),
        }
    }

    /// [`Structure::closest_hit_camera`], counting node and triangle tests in `stats` (the eye
    /// buffer's cell lookup counts as one inner node).
    pub fn closest_hit_camera_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let via_eye = self
            .eye
            .as_ref()
            .and_then(|e| e.closest_hit_leaving_with_stats(&self.global, ray, stats));
        match via_eye {
            Some(found) => found.map(|(hit, _)| hit),
            None => self.global.closest_hit_with_stats(ray, stats),
        }
    }

    /// Whether anything blocks the shadow segment `ray` toward light `light`.
    #[inline]
    pub fn occluded(&self, light: usize, ray: &Ray) -> bool {
        self.occluded_in(light, self.cell(light, ray), ray, &mut ())
    }

    /// [`Structure::occluded`], counting node and triangle tests in `stats` (a light buffer's
    /// cell lookup, and the `thesis` octree's, counts as one inner node).
    #[inline]
    pub fn occluded_counted(&self, light: usize, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.occluded_in(light, self.cell(light, ray), ray, stats)
    }

    /// The light buffer cell that answers the segment `ray` toward `light`, or `NO_CELL`.
    #[inline(always)]
    fn cell(&self, light: usize, ray: &Ray) -> u32 {
        match self.buffer_of[light] {
            NO_BUFFER => NO_CELL,
            b => self.buffers[b as usize]
                .cell_of(&self.global, ray)
                .unwrap_or(NO_CELL),
        }
    }

    /// Whether this structure answers shadow segments fastest in batches
    /// ([`Structure::occluded_batch`]) rather than each where it is made. `lights` with a light
    /// buffer does: it answers a batch cell by cell. The global BVH does not: a segment leaves
    /// the point the closest hit just found, whose nodes and triangles are then in the caches,
    /// and a batch loses that (Sponza: the frame took 1.08-1.11x with its segments batched).
    pub fn answers_in_batches(&self) -> bool {
        !self.buffers.is_empty()
    }

    /// Answers every segment of `segments` into `answers` (one each), as
    /// [`Structure::occluded`] does, in the order this structure answers fastest: `lights`
    /// takes them cell by cell of its light buffers (each cell's segments in their order, then
    /// those no buffer answers), the others as given. `order` is scratch kept between batches.
    /// Panics if `answers` is shorter than `segments`.
    pub fn occluded_batch(
        &self,
        segments: &[ShadowRay],
        answers: &mut [bool],
        order: &mut BatchOrder,
    ) {
        self.for_each_in_order(segments, order, |i, cell| {
            let s = &segments[i];
            answers[i] = self.occluded_in(s.light as usize, cell, &s.ray, &mut ());
        });
    }

    /// [`Structure::occluded_batch`], adding the segments' tests to `tests` (each counted as
    /// [`Structure::occluded_counted`] counts it: the order changes no count).
    pub fn occluded_batch_counted(
        &self,
        segments: &[ShadowRay],
        answers: &mut [bool],
        tests: &mut ShadowTests,
        order: &mut BatchOrder,
    ) {
        self.for_each_in_order(segments, order, |i, cell| {
            let s = &segments[i];
            let mut stats = TraversalStats::default();
            answers[i] = self.occluded_in(s.light as usize, cell, &s.ray, &mut stats);
            tests.add(&stats);
        });
    }

    /// Calls `answer(segment index, light buffer cell or NO_CELL)` for every segment, in the
    /// order this structure answers fastest.
    #[inline(always)]
    fn for_each_in_order(
        &self,
        segments: &[ShadowRay],
        order: &mut BatchOrder,
        mut answer: impl FnMut(usize, u32),
    ) {
        if self.buffers.is_empty() {
            (0..segments.len()).for_each(|i| answer(i, NO_CELL));
            return;
        }
        // Keys: the buffers' cells one after another, then one key for the other segments.
        order.bases.clear();
        let mut keys = 0;
        for b in &self.buffers {
            order.bases.push(keys as u32);
            keys += b.cells();
        }
        order.cells.clear();
        order.keys.clear();
        for s in segments {
            let cell = self.cell(s.light as usize, &s.ray);
            order.cells.push(cell);
            order.keys.push(match cell {
                NO_CELL => keys as u32,
                c => order.bases[self.buffer_of[s.light as usize] as usize] + c,
            });
        }
        order.sort_by_keys(keys + 1);
        // The segments are read out of order: fetch each a few answers ahead.
        for (k, &(i, cell)) in order.order.iter().enumerate() {
            if let Some(&(next, _)) = order.order.get(k + PREFETCH_AHEAD) {
                prefetch_all(&segments[next as usize]);
            }
            answer(i as usize, cell);
        }
    }

    /// The answer for a segment toward `light` whose light buffer cell is `cell` (or
    /// `NO_CELL`), counting into `stats` (or, with `()`, not at all).
    #[inline(always)]
    fn occluded_in(
        &self,
        light: usize,
        cell: u32,
        ray: &Ray,
        stats: &mut impl ShadowCounts,
    ) -> bool {
        if cell != NO_CELL {
            let buffer = &self.buffers[self.buffer_of[light] as usize];
            if let Some(answer) = stats.in_cell(buffer, cell, &self.global, ray) {
                return answer;
            }
        }
        stats.fallback(self, ray)
    }
}

/// Counting a shadow segment's tests, or not: the two queries of every part of a structure.
trait ShadowCounts {
    fn in_cell(
        &mut self,
        buffer: &LightBuffer,
        cell: u32,
        scene: &WideBvh8,
        ray: &Ray,
    ) -> Option<bool>;
    /// The answer of the global BVH, or of the `thesis` structure where that is built.
    fn fallback(&mut self, structure: &Structure, ray: &Ray) -> bool;
}

impl ShadowCounts for () {
    #[inline(always)]
    fn in_cell(
        &mut self,
        buffer: &LightBuffer,
        cell: u32,
        scene: &WideBvh8,
        ray: &Ray,
    ) -> Option<bool> {
        buffer.occluded_in_cell(cell, scene, ray)
    }
    #[inline(always)]
    fn fallback(&mut self, structure: &Structure, ray: &Ray) -> bool {
        match &structure.thesis {
            Some(t) => t.occluded(ray),
            None => structure.global.any_hit(ray),
        }
    }
}

impl ShadowCounts for TraversalStats {
    #[inline(always)]
    fn in_cell(
        &mut self,
        buffer: &LightBuffer,
        cell: u32,
        scene: &WideBvh8,
        ray: &Ray,
    ) -> Option<bool> {
        buffer.occluded_in_cell_with_stats(cell, scene, ray, self)
    }
    #[inline(always)]
    fn fallback(&mut self, structure: &Structure, ray: &Ray) -> bool {
        match &structure.thesis {
            Some(t) => t.occluded_counted(ray, self),
            None => structure.global.any_hit_with_stats(ray, self),
        }
    }
}
