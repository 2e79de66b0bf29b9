"""Sensors beyond cameras and joints: tactile grids, keyboard contact grids."""
