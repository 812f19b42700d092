//! Where a SAH build's time goes, by node size: `cargo run --release -p rdbvh-benches --example
//! build_by_size -- SCENE`. Builds the scene with `Builder::sah()`'s settings but a termination
//! that makes every node of at most `k` primitives a leaf at once, for `k` from 1 (the real
//! build) up to 4096, in interleaved rounds (best thread CPU time of 9). The difference between
//! two rows is the time the nodes between the two sizes take, with their splits, partitions and
//! node writes.

use rdbvh_core::builder::{BuildConfig, Builder};
use rdbvh_core::heuristics::{AllAxes, Sah, SahTermination, Termination};

/// [`SahTermination`], and every node of at most `.0` primitives a leaf before it is priced.
#[derive(Clone, Copy)]
struct StopAt(u32);

impl Termination for StopAt {
    fn must_stop(&self, count: u32, depth: u32) -> bool {
        count <= self.0 || SahTermination::default().must_stop(count, depth)
    }
    fn prefer_leaf(&self, count: u32, leaf: f32, split: f32) -> bool {
        SahTermination::default().prefer_leaf(count, leaf, split)
    }
}

fn main() {
    let Some(scene) = std::env::args().nth(1) else {
        eprintln!("usage: build_by_size SCENE");
        std::process::exit(2);
    };
    let tris = match rdbvh_benches::load_scene(&scene) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let sizes = [1u32, 3, 4, 8, 16, 32, 64, 256, 4096];
    let mut best = [f64::INFINITY; 9];
    for _ in 0..9 {
        for (slot, &k) in best.iter_mut().zip(&sizes) {
            let builder = Builder::new(AllAxes, Sah, StopAt(k), BuildConfig::default());
            let t0 = rdbvh_benches::thread_cpu_seconds();
            let bvh = builder
                .build(std::hint::black_box(&tris))
                .expect("finite scene");
            *slot = slot.min(rdbvh_benches::thread_cpu_seconds() - t0);
            drop(std::hint::black_box(bvh));
        }
    }
    println!(
        "{scene}: {} triangles; thread CPU, best of 9 rounds",
        tris.len()
    );
    for (k, t) in sizes.iter().zip(best) {
        println!(
            "  nodes of at most {k:>4} primitives made leaves: {:7.2} ms",
            t * 1e3
        );
    }
}
