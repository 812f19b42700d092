//! The host's clock for the core's build-phase profiles.

use std::time::Instant;

use rdbvh_core::builder::Clock;

/// Nanoseconds since the clock was made, from `std::time::Instant` (monotonic).
#[derive(Clone, Copy, Debug)]
pub struct StdClock {
    origin: Instant,
}

impl StdClock {
    /// A clock starting now.
    pub fn new() -> Self {
        Self {
            origin: Instant::now(),
        }
    }
}

impl Default for StdClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for StdClock {
    #[inline]
    fn now_ns(&self) -> u64 {
        self.origin.elapsed().as_nanos() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rdbvh_core::builder::{BuildArena, Builder};
    use rdbvh_core::bvh::Bvh;
    use rdbvh_core::geometry::Triangle;
    use rdbvh_core::Vec3;

    #[test]
    fn profiled_build_counts_and_times_phases_and_builds_the_same_tree() {
        let tris: Vec<Triangle> = (0..2000)
            .map(|i| {
                let o = Vec3::new((i % 50) as f32, (i / 50) as f32, (i % 7) as f32);
                Triangle::new(o, o + Vec3::X * 0.7, o + Vec3::Y * 0.7)
            })
            .collect();
        let builder = Builder::sah();
        let mut arena = BuildArena::with_capacity(tris.len());
        arena.load_triangles(&tris).unwrap();
        let mut bvh = Bvh::default();
        let stats = builder
            .build_into_profiled(&mut arena, &mut bvh, &StdClock::new())
            .unwrap();
        assert_eq!(bvh, builder.build(&tris).unwrap());
        let p = stats.profile;
        assert!(
            p.choose_calls > 0 && p.cost_calls >= p.choose_calls,
            "{p:?}"
        );
        assert!(p.cost_ns > 0, "{p:?}");
        // Without a clock the counts are the same and the times zero.
        arena.load_triangles(&tris).unwrap();
        let quiet = builder.build_into(&mut arena, &mut bvh).unwrap().profile;
        assert_eq!(
            (quiet.choose_calls, quiet.cost_calls),
            (p.choose_calls, p.cost_calls)
        );
        assert_eq!((quiet.choose_ns, quiet.cost_ns), (0, 0));
    }
}
