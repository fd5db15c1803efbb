import pytest
import torch

from keyin.lit.interpolator import InterpolatorModule
from keyin.lit.keyframes import KeyframeModule

STAGE1 = dict(
    image_size=8, channels=1, n_cond=2, n_future=6, max_offset=3, embed_dim=8, conv_width=4,
    coord_channels=True, norm="group", latent_dim=0, lstm_hidden=16, lstm_layers=1, mlp_hidden=16,
    step_input="boundaries", offset_min=1, offset_max=3, kl_weight=0.0, ae_weight=1.0, lr=1e-3,
)


def keyframe_module(
    teacher_weight: float, offset_evidence: bool = False, discovery: str = "offsets", teacher_chain: bool = False,
    teacher_leaves: bool = False, **sizes: int,
) -> KeyframeModule:
    """A small stage-2 module; ``sizes`` override STAGE1's (e.g. image_size, channels)."""
    torch.manual_seed(0)
    stage1 = dict(InterpolatorModule(**{**STAGE1, **sizes}).hparams)
    module = KeyframeModule.from_flat(
        stage1=stage1, n_keyframes=3, latent_dim=4, lstm_hidden=16, lstm_layers=1, attn_scale=True,
        offset_mode="predicted", fixed_offset=None, beta_ke=1.0, beta_ki=0.0, beta_kl=0.05,
        normalize_key_targets=True, lr=1e-3, teacher_weight=teacher_weight, teacher_clips=2,
        offset_evidence=offset_evidence, discovery=discovery, teacher_chain=teacher_chain, teacher_leaves=teacher_leaves,
    )
    module.log = module.log_dict = lambda *args, **kwargs: None  # no trainer attached
    return module


def batch() -> dict[str, torch.Tensor]:
    torch.manual_seed(1)
    return {
        "frames": (torch.rand(3, 8, 1, 8, 8) > 0.8).float(),
        "future_length": torch.tensor([6, 6, 4]),
        "keyframes": torch.zeros(3, 6, dtype=torch.bool),
    }


def test_teacher_adds_an_offset_cross_entropy_that_trains_the_predictor_only():
    plain = keyframe_module(0.0)._shared_step(batch(), "train")
    module = keyframe_module(10.0)
    terms = module._shared_step(batch(), "train")
    assert "teacher" not in plain and terms["teacher"] > 0
    assert torch.isclose(terms["loss"], plain["loss"] + 10.0 * terms["teacher"])
    module.zero_grad()
    terms["teacher"].backward()
    assert module.model.predictor.offset_head.weight.grad.abs().sum() > 0
    frozen = [*module.model.encoder.parameters(), *module.model.decoder.parameters(), *module.model.interpolator.parameters()]
    assert all(p.grad is None for p in frozen)


def test_teacher_is_not_used_in_validation():
    terms = keyframe_module(10.0)._shared_step(batch(), "val")
    assert "teacher" not in terms


def test_with_offset_evidence_the_teacher_also_trains_the_boundary_scores():
    module = keyframe_module(10.0, offset_evidence=True)
    terms = module._shared_step(batch(), "train")
    module.zero_grad()
    terms["teacher"].backward()
    assert module.model.predictor.boundary_head.weight.grad.abs().sum() > 0
    assert module.model.predictor.boundary_head.bias.grad.abs() > 0


def test_boundary_discovery_decodes_the_boundary_scores_and_offsets_stay_scored():
    module = keyframe_module(0.0, offset_evidence=True, discovery="boundaries").reader()
    with torch.no_grad():
        module.model.predictor.boundary_head.bias.fill_(-5.0)  # no boundary anywhere but where the
        module.model.predictor.boundary_head.weight.zero_()  # per-frame scores are forced below
    assert list(module.discoverers("keyin")) == ["keyin", "keyin_offsets", "keyin_map"]
    data = batch()
    found = module.discover(data["frames"], data["future_length"])
    assert found == [[2], [2], [2, 3]]  # gaps ≤ S = 3 force one interior keyframe; the 4-frame clip ends at 3
    offsets = module.discoverers("keyin")["keyin_offsets"](data["frames"], data["future_length"])
    assert all(all(0 <= p < n for p in row) for row, n in zip(offsets, [6, 6, 4]))
    mapped = module.discover(data["frames"], data["future_length"], discovery="map")
    assert all(all(0 <= p < n - 1 for p in row) for row, n in zip(mapped[:2], [6, 6]))
    assert mapped[2][-1] == 3 and all(0 <= p < 3 for p in mapped[2][:-1])
    assert list(keyframe_module(0.0).reader().discoverers("jumpy")) == ["jumpy"]
    with pytest.raises(ValueError, match="needs offset_evidence"):
        keyframe_module(0.0, discovery="boundaries")


def test_the_chained_teacher_scores_delta_read_along_the_teachers_own_path():
    from keyin.decode.teacher import segmentation_targets
    from keyin.losses.soft_keyframe import boundary_teacher_loss, offset_teacher_loss

    module = keyframe_module(10.0, offset_evidence=True, teacher_chain=True)
    data = batch()
    clips, lengths = data["frames"], data["future_length"]
    torch.manual_seed(5)
    terms = module._shared_step(data, "train")
    torch.manual_seed(5)  # the same posterior samples, then the teacher's targets and δ on its path
    out = module.model(clips, lengths)
    offsets, boundaries = segmentation_targets(module.model.interpolator, out["boundary_emb"][:2], lengths[:2], 3)
    chained = module.model.keyframes(clips[:2], lengths[:2], chain=offsets)[1]
    expected = offset_teacher_loss(chained.offset_logits, offsets) + boundary_teacher_loss(
        out["boundary_scores"][:2], boundaries, lengths[:2]
    )
    assert torch.isclose(terms["teacher"], expected)
    unchained = keyframe_module(10.0, offset_evidence=True)
    torch.manual_seed(5)
    assert not torch.isclose(unchained._shared_step(data, "train")["teacher"], expected)


def test_a_leaving_teacher_adds_the_offset_out_of_the_clip_to_its_targets():
    data = batch()
    torch.manual_seed(5)
    plain = keyframe_module(10.0, offset_evidence=True)._shared_step(data, "train")["teacher"]
    torch.manual_seed(5)
    leaving = keyframe_module(10.0, offset_evidence=True, teacher_leaves=True)._shared_step(data, "train")["teacher"]
    assert not torch.isclose(plain, leaving)
