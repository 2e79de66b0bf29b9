"""Interactive language-instruction rollout over a local socket."""
