"""rmb-collect --cycle-instructions: any N episodes cover min(N, 18) of Pick's instructions."""

from __future__ import annotations

from collections import Counter

import pytest

from rmb_lerobot.envs.collect import variant_of

PICK_INSTRUCTIONS, PICK_WORLDS = 18, 6


@pytest.mark.parametrize("episodes", [1, 5, 6, 17, 18, 30, 36, 108])
def test_any_number_of_episodes_covers_as_many_instructions_as_it_can(episodes):
    variants = [variant_of(i, PICK_INSTRUCTIONS, PICK_WORLDS) for i in range(episodes)]
    assert len(set(variants)) == min(episodes, PICK_INSTRUCTIONS)  # 30 covered 5 before
    counts = Counter(variants).values()
    assert max(counts) - min(counts) <= 1  # as even as the number allows


@pytest.mark.parametrize(("variants", "worlds"), [(18, 6), (18, 2), (4, 6), (5, 3), (1, 6)])
def test_variants_times_worlds_episodes_hold_every_pair_once(variants, worlds):
    pairs = {(variant_of(i, variants, worlds), i % worlds) for i in range(variants * worlds)}
    assert len(pairs) == variants * worlds
