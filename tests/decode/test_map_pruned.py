"""Discovery ``map_pruned``: the exact best segmentation among candidate keyframes, against brute force."""

import pytest
import torch

from keyin.decode.registry import rule_named
from keyin.decode.rules import map_keyframes
from keyin.decode.segment_costs import candidate_segments, interpolation_costs
from keyin.models import ConvDecoder, Interpolator
from tests.decode.enumeration import cheapest_keyframes, keyframe_sets, random_map_inputs


def test_candidate_segments_match_a_brute_force():
    generator = torch.Generator().manual_seed(0)
    n_future, max_offset, n_keyframes = 7, 3, 3
    candidates = torch.rand(40, n_future, generator=generator) < 0.4
    lengths = torch.randint(1, n_future + 1, (40,), generator=generator)
    keep = candidate_segments(candidates, lengths, max_offset, n_keyframes)
    assert keep.shape == (40, n_future, max_offset)
    for b, length in enumerate(lengths.tolist()):
        interior = [p for p in range(length - 1) if candidates[b, p]]  # the closing frame is a boundary anyway
        allowed = {0, length} | {p + 1 for p in interior}
        feasible = any(set(chosen) <= set(interior) for chosen in keyframe_sets(length, max_offset, n_keyframes))
        for start in range(n_future):
            for offset in range(1, max_offset + 1):
                inside = start + offset <= length
                expected = inside and (not feasible or (start in allowed and start + offset in allowed))
                assert bool(keep[b, start, offset - 1]) == expected, (b, start, offset)


def test_pruned_costs_are_the_full_costs_of_the_kept_segments():
    torch.manual_seed(1)
    interpolator = Interpolator(8, 4, 0, 16, 1, 16).eval()
    decoder = ConvDecoder(8, 1, 4, 8, norm="none").eval()
    boundary_emb, frames = torch.rand(3, 9, 8), torch.rand(3, 8, 64)
    keep = candidate_segments(torch.rand(3, 8) < 0.5, torch.tensor([8, 8, 6]), 4, 4)
    full = interpolation_costs(interpolator, decoder, boundary_emb, frames)
    pruned = interpolation_costs(interpolator, decoder, boundary_emb, frames, keep=keep, chunk=5)
    torch.testing.assert_close(pruned[keep], full[keep])
    assert torch.isinf(pruned[~keep]).all()


def test_a_videos_pruned_costs_in_blocks_are_its_full_costs_of_the_kept_segments():
    from keyin.decode.segment_costs import video_interpolation_costs

    torch.manual_seed(3)
    interpolator = Interpolator(8, 4, 0, 16, 1, 16).eval()
    decoder = ConvDecoder(8, 1, 4, 8, norm="none").eval()
    embeddings, frames = torch.rand(23, 8), torch.randint(0, 256, (23, 64), dtype=torch.uint8)
    keep = torch.rand(22, 4) < 0.3
    keep[5:10] = False  # a block with nothing to render
    full = video_interpolation_costs(interpolator, decoder, embeddings, frames, block=5)
    pruned = video_interpolation_costs(interpolator, decoder, embeddings, frames, block=5, keep=keep)
    torch.testing.assert_close(pruned[keep], full[keep])
    assert torch.isinf(pruned[~keep]).all()
    with pytest.raises(ValueError, match="keep must be"):
        video_interpolation_costs(interpolator, decoder, embeddings, frames, keep=keep[:-1])


def test_map_among_candidates_is_the_best_segmentation_whose_keyframes_are_candidates():
    """Brute force over every keyframe set inside the candidates (every set where none covers the clip),
    clips of two lengths; the same keyframes from precomputed costs, masked."""
    n_future, max_offset, n_keyframes = 7, 3, 4
    interpolator, decoder, boundary_emb, frames, scores = random_map_inputs(6, n_future, max_offset, seed=2)
    candidates = torch.rand(6, n_future) < 0.5
    candidates[0] = False  # no candidate: no segmentation of 7 frames with gaps ≤ 3 → every frame may be one
    lengths = torch.tensor([7, 7, 7, 5, 5, 7])
    price, weight = 30.0, 2.0
    keep = candidate_segments(candidates, lengths, max_offset, n_keyframes)
    decoded = map_keyframes(interpolator, decoder, boundary_emb, frames, lengths, n_keyframes, price, scores, weight,
                            keep=keep)
    bce = interpolation_costs(interpolator, decoder, boundary_emb, frames)
    from_costs = map_keyframes(interpolator, decoder, boundary_emb, frames, lengths, n_keyframes, price, scores, weight,
                               costs=bce, keep=keep)
    assert from_costs == decoded
    for b, length in enumerate(lengths.tolist()):
        sets = keyframe_sets(length, max_offset, n_keyframes)
        inside = [chosen for chosen in sets if all(candidates[b, p] for p in chosen)]
        assert decoded[b] == cheapest_keyframes(bce[b], scores[b], inside or sets, length, price, weight), b
    assert not any(candidates[0]) and decoded[0]  # the fallback found keyframes all the same


def test_map_pruned_needs_boundary_scores_and_keeps_maps_keyframes_when_every_frame_is_a_candidate():
    from tests.planning.trained_models import keyframe_module

    clips, lengths = torch.rand(4, 7, 3, 16, 16), torch.tensor([6, 6, 4, 6])
    plain = keyframe_module().eval()
    with pytest.raises(ValueError, match="boundary scores"):
        rule_named("map_pruned")(plain.model, clips, lengths)
    with pytest.raises(ValueError, match="needs offset_evidence"):
        keyframe_module(discovery="map_pruned")
    module = keyframe_module(offset_evidence=True, discovery="map_pruned").eval().reader()
    module.saved_prices = module.prices(candidate_logit=-float("inf"))  # every frame a candidate
    for price in (0.0, "knee"):
        exact = module.discover(clips, lengths, "map", keyframe_cost=price)
        assert module.discover(clips, lengths, "map_pruned", keyframe_cost=price) == exact
        assert sum(map(len, exact)) > len(exact)  # more than the closing keyframes: not a forced answer
    assert set(module.discoverers("keyin_plus", ["map", "map_pruned"])) == {"keyin_plus_map", "keyin_plus"}


def test_precomputed_costs_must_hold_every_segment_the_rule_prices():
    from tests.planning.trained_models import keyframe_module

    module = keyframe_module(offset_evidence=True).eval().reader()
    module.saved_prices = module.prices(candidate_logit=-float("inf"))
    clips, lengths = torch.rand(2, 7, 3, 16, 16), torch.tensor([6, 6])
    costs = torch.full((2, 6, 3), float("inf"))  # nothing computed
    with pytest.raises(ValueError, match="costs lack segments"):
        module.discover(clips, lengths, "map_pruned", keyframe_cost=0.0, costs=costs)
