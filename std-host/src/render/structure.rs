//! The acceleration structure the integrator traces through, chosen with `--structure`.
//!
//! Camera and bounce rays always go through the global BVH. Shadow rays go through the
//! structure: with `global` the same BVH, with `lights` the light buffer of the ray's light when
//! it has one, and the global BVH for every segment the buffer does not answer, with `thesis`
//! the thesis's influence areas, octree and fallback ([`super::ThesisStructure`]). All answer every query
//! exactly as the global BVH does, so the images are byte-identical.

use std::time::Instant;

use rdbvh_core::builder::{parallel, BuildOptions, Preset};
use rdbvh_core::bvh::{Hit, TraversalStats, WideBvh8};
use rdbvh_core::geometry::{Ray, Triangle, TriangleEdges};
use rdbvh_core::light_buffer::LightBuffer;

use super::light_structure::light_buffers;
use super::thesis::ThesisStructure;
use super::{Light, RenderError};

/// Which structure answers the shadow rays (`--structure`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StructureKind {
    /// The global BVH: binned SAH with reinsertion (Bittner et al. 2013), collapsed to 8-wide
    /// nodes, the fastest single BVH rdbvh builds for these rays.
    Global,
    /// A light buffer per light (per cluster of emissive triangles), built from the lights
    /// automatically and kept where a pilot frame's shadow rays show that it pays
    /// ([`super::pilot`]), with the global BVH for what a buffer does not answer.
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
    /// The `thesis` structure, which owns the global BVH as its fallback (`global` is then
    /// empty: no second copy).
    thesis: Option<ThesisStructure>,
    build_ms: f64,
    /// The global BVH's share of `build_ms`.
    global_build_ms: f64,
}

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

    /// The closest hit of a camera or bounce ray, with its triangle's first vertex and edges
    /// from the leaf block that held it: always the global BVH.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<(Hit, TriangleEdges)> {
        self.global().closest_hit_edges(ray)
    }

    /// Whether anything blocks the shadow segment `ray` toward light `light`.
    #[inline]
    pub fn occluded(&self, light: usize, ray: &Ray) -> bool {
        if let Some(t) = &self.thesis {
            return t.occluded(ray);
        }
        let buffer = self.buffer_of[light];
        if buffer != NO_BUFFER {
            if let Some(answer) = self.buffers[buffer as usize].occluded(&self.global, ray) {
                return answer;
            }
        }
        self.global().any_hit(ray)
    }

    /// [`Structure::occluded`], counting node and triangle tests in `stats` (a light buffer's
    /// cell lookup, and the `thesis` octree's, counts as one inner node).
    #[inline]
    pub fn occluded_counted(&self, light: usize, ray: &Ray, stats: &mut TraversalStats) -> bool {
        if let Some(t) = &self.thesis {
            return t.occluded_counted(ray, stats);
        }
        let buffer = self.buffer_of[light];
        if buffer != NO_BUFFER {
            let buffer = &self.buffers[buffer as usize];
            if let Some(answer) = buffer.occluded_with_stats(&self.global, ray, stats) {
                return answer;
            }
        }
        self.global().any_hit_with_stats(ray, stats)
    }
}
