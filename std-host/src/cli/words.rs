//! Numbers in words for the commands' summaries.

/// `n` things in words: "1 thread", "2 threads".
pub(super) fn count(n: usize, thing: &str) -> String {
    format!("{n} {thing}{}", if n == 1 { "" } else { "s" })
}
