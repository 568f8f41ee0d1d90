"""Physics layer: geometry, rotations and the Earth rate (no I/O, no bench)."""
