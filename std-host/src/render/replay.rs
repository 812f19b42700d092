//! `shadow_ms`: the frame's shadow segments traced again on one thread, best of several rounds,
//! through the structure alone, without counters, in the frame's batches (each answered in the
//! structure's order, as the frame answered it). This times what a structure costs the shadow
//! rays, apart from shading, sampling and threads; a frame with more than
//! [`super::REPLAY_CAP`] shadow segments replays its first ones.

use std::time::Instant;

use super::{BatchOrder, RenderError, ShadowRay, Structure};

/// The best time, in milliseconds, of `rounds` single-thread replays of `shadow` through
/// `structure`, in batches of the sizes `batches` (in order; what they do not cover is one more
/// batch). Every answer must be the frame's: a replay that disagrees is a bug in a structure
/// (or a lost determinism), and fails.
pub fn replay_shadow_rays(
    structure: &Structure,
    shadow: &[ShadowRay],
    batches: &[usize],
    rounds: u32,
) -> Result<f64, RenderError> {
    let mut best = f64::INFINITY;
    let mut answers = vec![false; shadow.len()];
    let mut order = BatchOrder::default();
    for _ in 0..rounds.max(1) {
        let start = Instant::now();
        answer_batches(structure, shadow, batches, &mut answers, &mut order);
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

/// Answers `shadow` into `answers` through `structure` in batches of the sizes `batches` (in
/// order; what they do not cover is one more batch), each as [`Structure::occluded_batch`] does.
pub fn answer_batches(
    structure: &Structure,
    shadow: &[ShadowRay],
    batches: &[usize],
    answers: &mut [bool],
    order: &mut BatchOrder,
) {
    let mut first = 0usize;
    for &n in batches.iter().chain([&usize::MAX]) {
        let end = first.saturating_add(n).min(shadow.len());
        structure.occluded_batch(&shadow[first..end], &mut answers[first..end], order);
        first = end;
    }
}

fn blocked(occluded: bool) -> &'static str {
    if occluded {
        "blocked"
    } else {
        "clear"
    }
}
