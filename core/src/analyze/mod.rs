//! The BVH analyzer: composable per-node and final actions run in one walk of a tree, kept apart
//! from construction so that measuring never changes what is built.
