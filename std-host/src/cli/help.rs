//! The long help texts after the options (`after_help`): what the formats and presets are, so a
//! user can go from `--help` to a working command without reading the source.

/// Scenes, shown by every command.
pub const SCENES: &str = "\
Scenes: SCENE.obj is a Wavefront OBJ file (triangulated, all objects in file order; its .mtl
gives material names and emissive flags, and a missing .mtl is only a warning), or one of:
  builtin:random100    the thesis's Random100 (100 random triangles, std::mt19937 seed 1)
  builtin:random1000   the thesis's Random1000 (the next 1000 triangles of that stream)
  builtin:room         a closed room with an emissive ceiling light and three boxes";

/// The top-level help.
pub fn top() -> String {
    format!(
        "{SCENES}\n\n\
         Influence areas (--areas AREAS.toml): see `rdbvh build --help`.\n\n\
         Run with no arguments for a short demo that checks itself against brute force."
    )
}

const PRESETS: &str = "\
Presets (--preset NAME; the thesis's four pairs, and this project's sah and pah):
  sah        binned SAH over all three axes (the state of the art; the fallback BVH)
  standard   SAH + longest axis (LSPH)
  facing     SAH + splitting plane facing (SPFH)       needs --areas
  longest    PAH + LSPH                                needs --areas
  full       PAH + SPFH                                needs --areas
  pah        PAH over all three axes (sah's builder)   needs --areas
--thesis-mode builds as the thesis did: 41 bins over the node box, leaves of at most 2 triangles by
size alone; --bins and --max-leaf still override it. --builder sah|lsph is the plain binned SAH
builder (all axes, or the longest axis only); it and --preset exclude each other. The thesis cut
rule of standard, facing, longest and full tries the chooser's axes in order, also the next ones
when they are nearly as good, accepts a good split early and falls back to SAH on the longest
axis; so --preset standard and --builder lsph build different trees.";

const AREAS: &str = "\
Area files (TOML): one [[area]] table per influence area, with the keys of an experiments.toml
[[config]] entry (vectors are arrays of 3 numbers; `normal` and `direction` need not be unit):
  [[area]]
  kind = \"plane\"              # parallel rays: an oriented box in front of a planar light
  center = [5.0, 9.9, 5.0]    # centre of the light rectangle
  normal = [0, -1, 0]         # the ray direction
  half_width = 1.0            # half extents of the rectangle (look-at frame, world up +y)
  half_height = 1.0
  depth = 9.9                 # how far the box reaches along `normal`
  [[area]]
  kind = \"point\"              # radial rays: a frustum from a point or spot light
  eye = [5.0, 9.5, 5.0]
  direction = [0, -1, 0]
  fov_x_deg = 90.0            # full fields of view, strictly between 0 and 180
  fov_y_deg = 60.0
  near = 0.1
  far = 9.4
The keys scene, file, orientation and thesis_test are allowed and ignored here (experiment
reads them: see its help), so an entry can be pasted from experiments.toml. A file of [[config]]
tables instead (experiments.toml itself) is a list of experiments: only the entries whose `file`
names the scene (same file name without extension, any case; builtin:random100 takes
Random100.obj's) are used.";

/// `rdbvh build --help`.
pub fn build() -> String {
    format!(
        "{PRESETS}\n\n\
         With --areas, the BVH holds only the triangles that overlap the first area that applies to\n\
         the scene (separating-axis test, the scene structure's own), and the report adds pah_cost:\n\
         the expected cost per ray of the area's rays under its PAH. Both costs use C_trav =\n\
         C_isect = 1, or with --thesis-mode the thesis's 2 x 1.0 per inner node and 1.2 per\n\
         triangle (as analyze and experiment report them).\n\
         The build runs on every thread (RAYON_NUM_THREADS sets how many) and makes the\n\
         single-threaded build's tree, node for node; build_ms is its wall time.\n\
         --json prints one object with the keys scene, triangles (in the build), scene_triangles,\n\
         nodes, leaves, max_depth, sah_cost, pah_cost, bytes, load_ms, select_ms, build_ms,\n\
         reinsert_ms, reinsert_moved, mtris_per_s, threads, builder, preset, thesis_mode,\n\
         area_kind, bins, max_leaf (null where they do not apply, and for a cost that is NaN:\n\
         coordinates of about 1e19 or more overflow box areas).\n\n\
         {AREAS}\n\n\
         Examples:\n  \
         rdbvh build scene.obj --preset sah --json\n  \
         rdbvh build WoodScene.obj --preset full --areas experiments.toml --thesis-mode\n\n\
         {SCENES}"
    )
}

/// `rdbvh trace --help`.
pub fn trace() -> String {
    format!(
        "Without --areas, one BVH over the scene answers every ray (--builder, or --preset sah or\n\
         standard), traversed as its 4-wide collapse (same answers, faster). With --areas, rays are\n\
         answered through the scene structure: an octree (or a list) finds the areas that may\n\
         contain a ray's origin; a ray affine to one (origin inside, direction within 1 degree of\n\
         the area's) searches that area's local BVH (built with --preset, default pah) up to where\n\
         it leaves the area, and otherwise the fallback BVH (binned SAH over the whole scene,\n\
         default settings) answers. The answers equal brute force either way. Standard error then\n\
         gets the local hit rate, the mean cost per ray (C_trav = C_isect = 1) with the structure\n\
         and with the fallback BVH alone on the same rays, and rays per second.\n\n\
         {PRESETS}\n\n\
         {AREAS}\n\n\
         Examples:\n  \
         rdbvh trace scene.obj --rays rays.csv --out hits.csv\n  \
         rdbvh trace WoodScene.obj --areas experiments.toml --preset full --rays rays.csv \\\n      \
         --out hits.csv --lookup octree --octree-levels 5 --max-tries 1\n\n\
         {SCENES}"
    )
}

/// `rdbvh render --help`.
pub fn render() -> String {
    format!(
        "What is modelled: Lambertian surfaces with the MTL Kd colour (textures are not read; a\n\
         material without Kd, or a triangle without a material, is 0.8 grey), geometric normals,\n\
         both faces of every triangle. Lights: emissive MTL Ke triangles (area lights, emitting\n\
         from both faces) and the lights file's point, spot (hard-edged cone) and quad lights\n\
         (one-sided, toward edge1 x edge2; not geometry, so the camera does not see them). No\n\
         environment light: rays that leave the scene are black.\n\
         Integrator: path tracing with next event estimation. At every vertex one light is chosen\n\
         in proportion to its power and one point on it (uniform by area), and one shadow segment\n\
         is traced, from the point offset along the normal by 1e-4 of the scene's largest\n\
         coordinate to 1 - 1e-4 of the way to the light sample; then a cosine-weighted bounce,\n\
         with Russian roulette from the third vertex on. Emission is added where a camera ray\n\
         lands; bounce rays add none (next event estimation counted it). Each random number is a\n\
         hash of (seed, pixel, sample, dimension), so an image depends on --seed alone, not on\n\
         --threads. The image is the mean of --spp samples, clamped to [0, 1], sRGB-encoded, 8\n\
         bits; 16 x 16 tiles run on the threads, with a progress bar when standard error is a\n\
         terminal.\n\
         Structures: bounce rays go through the global BVH (binned SAH, reinsertion, 8-wide\n\
         nodes). Shadow segments go through --structure: global, the same BVH; lights, a\n\
         light buffer per light (a cube map of directions around it, each cell holding a BVH of\n\
         what segments toward the light through that cell can hit; emissive triangles are\n\
         clustered per material, at most 32 buffers, for the most powerful lights), with the\n\
         global BVH for segments a buffer does not take. A pilot frame (1/8 of the resolution,\n\
         1 sample, traced through the global BVH first) decides: a light wider than half its\n\
         pilot segments' median length gets no buffer built, nor one whose pilot segments,\n\
         scaled to the frame's samples, would save fewer tests (half of theirs through the\n\
         global BVH) than 25 per scene triangle, about the buffer's build time; a buffer built\n\
         is kept only where those segments need at most 0.7 of the global BVH's node +\n\
         triangle tests through it; build_ms includes the pilot (global_build_ms is the\n\
         global BVH's part, pilot_ms the pilot frame's). With a buffer kept, paths are traced\n\
         in batches of consecutive tiles (about 32768 samples), and each batch's shadow\n\
         segments are answered together, cell by cell of the buffers, so that a cell's tree\n\
         stays in the caches; the radiance is then summed in each path's order, bit for bit\n\
         as if answered one by one. lights also gives the camera rays an eye buffer: the\n\
         buffer of a spot light at the eye whose cone is the view, each cell holding a BVH of\n\
         what the camera rays through it can hit. The pilot's camera rays (one per pixel)\n\
         decide it by the same two rules: built only if the frame's camera rays could repay\n\
         it, kept only at 0.7 of the global BVH's tests or fewer. Camera rays go through the\n\
         global BVH otherwise, and with global and thesis.\n\
         thesis, the thesis's own structure with influence areas made from the lights: six\n\
         90-degree frustums around a point light (one per cube face, apex at the light, to the\n\
         scene's far end), one frustum along a spot of at most 120 degrees (six for a wider one),\n\
         an oriented box in front of a quad light or an emissive cluster (both sides); a local\n\
         BVH per area (pah preset), an octree over the areas and the global BVH as the\n\
         fallback. A segment whose origin is inside an area and which runs toward its light\n\
         (within 1 degree of the radial direction for a frustum; ending inside the box for a\n\
         box) is answered by that area's local BVH up to where it leaves the area, the rest by\n\
         the fallback. Every structure answers exactly\n\
         as the global BVH does: the images are byte-identical.\n\
         shadow_ms is the best of --shadow-replays single-thread replays of the frame's shadow\n\
         segments (its first 2097152 when it has more) through the structure alone, without\n\
         counters, in the frame's batches; the replay's answers must equal the frame's.\n\
         --json prints one object as the last line, with the keys scene, triangles, lights,\n\
         light_buffers, light_buffers_dropped, light_buffers_skipped, pilot_shadow_rays,\n\
         eye_buffer (true when kept), eye_buffer_tests (its tests on the pilot's camera rays\n\
         over the global BVH's, 0 when not built), influence_areas, influence_area_triangles, width, height, spp, max_bounces, seed,\n\
         threads, structure, build_ms, global_build_ms, pilot_ms, render_ms, camera_rays,\n\
         shadow_rays, bounce_rays, shadow_occluded, shadow_node_tests, shadow_triangle_tests,\n\
         shadow_replay_rays, shadow_ms, mean_luminance and out.\n\
         --record-rays DIR writes the first --record-limit rays of each kind (in tile order, then\n\
         pixel, sample and path vertex) as `rdbvh trace --rays` reads them, with the renderer's\n\
         answers as `rdbvh trace --out` writes them: replay shadow_rays.csv with --any-hit.\n\n\
         Lights file (TOML), one [[light]] table per light, every field required:\n  \
         [[light]]\n  \
         kind = \"point\"\n  \
         position = [0.0, 1.9, 0.0]\n  \
         intensity = [5.0, 5.0, 5.0]       # radiant intensity, RGB, non-negative\n  \
         [[light]]\n  \
         kind = \"spot\"\n  \
         position = [0.0, 1.9, 0.0]\n  \
         direction = [0.0, -1.0, 0.0]\n  \
         angle_deg = 30.0                  # the cone's half-angle, in (0, 90]\n  \
         intensity = [5.0, 5.0, 5.0]\n  \
         [[light]]\n  \
         kind = \"quad\"                     # one-sided: emits toward edge1 x edge2\n  \
         corner = [-0.25, 1.98, -0.25]\n  \
         edge1 = [0.5, 0.0, 0.0]\n  \
         edge2 = [0.0, 0.0, 0.5]\n  \
         radiance = [10.0, 10.0, 10.0]\n\n\
         Examples:\n  \
         rdbvh render cornell_box.obj --spp 64 --out cornell.png\n  \
         rdbvh render builtin:room --eye 5,5,9.5 --look-at 5,4,0 --fov 70 --structure lights --json\n  \
         rdbvh render sponza.obj --lights lights.toml --record-rays rays/ --record-limit 10000\n\n\
         {SCENES}"
    )
}
