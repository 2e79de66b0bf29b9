"""rmb-benchmark: the paper's policies x tasks x seeds grid, as Ray tasks."""
