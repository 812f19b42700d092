//! `shadow_ms`: the frame's shadow segments traced again on one thread, best of several rounds,
//! through the structure alone, without counters. This times what a structure costs the shadow
//! rays, apart from shading, sampling and threads; a frame with more than
//! [`super::REPLAY_CAP`] shadow segments replays its first ones.

use std::time::Instant;

use super::{RenderError, ShadowRay, Structure};

/// The best time, in milliseconds, of `rounds` single-thread replays of `shadow` through
/// `structure`. Every answer must be the frame's: a replay that disagrees is a bug in a
/// structure (or a lost determinism), and fails.
pub fn replay_shadow_rays(
    structure: &Structure,
    shadow: &[ShadowRay],
    rounds: u32,
) -> Result<f64, RenderError> {
    let mut best = f64::INFINITY;
    let mut answers = vec![false; shadow.len()];
    for _ in 0..rounds.max(1) {
        let start = Instant::now();
        for (a, s) in answers.iter_mut().zip(shadow) {
            *a = structure.occluded(s.light as usize, &s.ray);
        }
        best = best.min(start.elapsed().as_secs_f64() * 1e3);
        if let Some(i) = (0..shadow.len()).find(|&i| answers[i] != shadow[i].occluded) {
            return Err(RenderError::Replay(format!(
                "shadow ray {i} (toward light {}) was {} in the frame and {} in the replay",
                shadow[i].light,
                blocked(shadow[i].occluded),
                blocked(answers[i])
            )));
        }
    }
    Ok(best)
}

fn blocked(occluded: bool) -> &'static str {
    if occluded {
        "blocked"
    } else {
        "clear"
    }
}
