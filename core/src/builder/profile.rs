//! Build-phase profiles: how long a build spends choosing split orientations and pricing
//! candidate planes. The core has no clock, so the caller lends one.

/// A monotonic time source in nanoseconds. The host passes one backed by `std::time::Instant`;
/// [`NoClock`] turns the timing off at no cost.
pub trait Clock {
    /// Nanoseconds since some fixed origin.
    fn now_ns(&self) -> u64;
}

/// No clock: every reading is 0, and the optimiser removes the timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoClock;

impl Clock for NoClock {
    #[inline(always)]
    fn now_ns(&self) -> u64 {
        0
    }
}

/// Time and calls per build phase, the thesis's profile columns. "Choose split plane" is the axis
/// chooser's orientation choice (LSPH, SPFH, all axes), once per node that is priced; "compute
/// cost" is one axis's sweep, which prices every candidate plane on it with the cost model. The
/// counts are exact with any clock; the times are zero with [`NoClock`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhaseProfile {
    /// Nanoseconds in the axis chooser.
    pub choose_ns: u64,
    /// Calls of the axis chooser.
    pub choose_calls: u64,
    /// Nanoseconds in the sweeps (cost-model evaluations of candidate planes).
    pub cost_ns: u64,
    /// Sweeps (one per axis priced).
    pub cost_calls: u64,
}

impl PhaseProfile {
    /// Adds another build's profile (for summing over threads or builds).
    pub fn add(&mut self, other: &PhaseProfile) {
        self.choose_ns += other.choose_ns;
        self.choose_calls += other.choose_calls;
        self.cost_ns += other.cost_ns;
        self.cost_calls += other.cost_calls;
    }
}
