"""rmb-data: inspect, compare, refine, extend and view RMB episodes."""
