"""The paper's open choices in stage 2 (issue 43): what the interpolator reads of δ, how the loss is
reduced, the stochastic interpolator's latent, the entropy aid, and a stage 1 taken from a stage-2
checkpoint."""

import pytest
import torch

from keyin.lit.checkpoints import load_checkpoint, load_stage1
from keyin.lit.interpolator import InterpolatorModule
from keyin.lit.keyframes import KeyframeModule
from keyin.lit.registry import load_trained_module, load_training_module
from keyin.losses.soft_keyframe import interpolation_loss, keyin_loss, offset_entropy
from keyin.models.config import KEYINConfig
from keyin.models.keyin import interpolator_offsets
from keyin.pretrained import resolve
from keyin.models.positions import position_distributions
from tests.lit.test_keyframe_teacher import STAGE1, batch


def module(**options) -> KeyframeModule:
    """A small stage-2 module with the given options; ``inter_latent`` sizes its stage 1's latent."""
    torch.manual_seed(0)
    stage1 = dict(InterpolatorModule(**{**STAGE1, "latent_dim": options.pop("inter_latent", 0)}).hparams)
    built = KeyframeModule.from_flat(
        stage1=stage1, n_keyframes=3, latent_dim=4, lstm_hidden=16, lstm_layers=1, attn_scale=True,
        offset_mode="predicted", fixed_offset=None, beta_ke=1.0, beta_ki=options.pop("beta_ki", 0.0), beta_kl=0.05,
        normalize_key_targets=True, lr=1e-3, **options,
    )
    built.log = built.log_dict = lambda *args, **kwargs: None  # no trainer attached
    return built


def test_the_straight_through_offsets_are_the_argmax_forward_and_the_soft_gradient_backward():
    torch.manual_seed(0)
    probs = torch.softmax(torch.randn(2, 3, 5), -1).requires_grad_(True)
    weights = torch.randn(2, 3, 5)
    straight = interpolator_offsets(probs, "straight_through")
    hard = torch.nn.functional.one_hot(probs.argmax(-1), 5).float()
    torch.testing.assert_close(straight, hard)
    (straight * weights).sum().backward()
    torch.testing.assert_close(probs.grad, weights)  # the gradient of the soft input itself
    assert not interpolator_offsets(probs, "argmax").requires_grad
    assert interpolator_offsets(probs, "soft") is probs
    with pytest.raises(ValueError, match="delta_input must be one of"):
        interpolator_offsets(probs, "hard")


def test_the_model_interpolates_with_the_offset_code_it_is_told_to_read():
    data = batch()
    soft, argmax = module(), module(delta_input="argmax")
    argmax.load_state_dict(soft.state_dict())
    with torch.no_grad():
        out_soft = soft.eval().model(data["frames"], data["future_length"], sample=False)
        out_argmax = argmax.eval().model(data["frames"], data["future_length"], sample=False)
        first = out_argmax["boundary_emb"][:, 0]
        hard = torch.nn.functional.one_hot(out_argmax["offset_probs"].argmax(-1), 3).float()
        expected = argmax.model.interpolate(first, out_argmax["key_emb"], hard)
    torch.testing.assert_close(out_soft["offset_probs"], out_argmax["offset_probs"])
    torch.testing.assert_close(out_argmax["frames"], expected)
    assert not torch.allclose(out_soft["frames"], out_argmax["frames"])


def loss_inputs():
    torch.manual_seed(3)
    b, m, s, n, d, e, z = 2, 2, 3, 4, 5, 3, 4
    return dict(
        offset_probs=torch.softmax(torch.randn(b, m, s), -1), key_emb_pred=torch.randn(b, m, e),
        future_emb=torch.randn(b, n, e), inter_frames_pred=torch.rand(b, m, s, d) * 0.8 + 0.1,
        future_frames=(torch.rand(b, n, d) > 0.5).float(), kl_per_key=torch.rand(b, m) * 3,
        lengths=torch.tensor([4, 3]), beta_ke=1.0, beta_ki=0.0, beta_kl=0.05, latent_dim=z,
    )


def test_each_reduction_scales_the_terms_it_says():
    inputs = loss_inputs()
    total = keyin_loss(**inputs, reduction="sum")
    per_frame = keyin_loss(**inputs, reduction="per_frame")
    per_pixel = keyin_loss(**inputs, reduction="per_pixel")
    _, frame_pos = position_distributions(inputs["offset_probs"])
    per_clip, _, _ = interpolation_loss(frame_pos, inputs["inter_frames_pred"], inputs["future_frames"], inputs["lengths"])
    lengths, pixels = inputs["lengths"].float(), inputs["future_frames"].shape[-1]
    torch.testing.assert_close(total["inter"], per_clip.mean())
    torch.testing.assert_close(per_frame["inter"], (per_clip / lengths).mean())
    torch.testing.assert_close(per_pixel["inter"], (per_clip / (lengths * pixels)).mean())
    torch.testing.assert_close(per_frame["key"], total["key"])  # the keyframe terms are per keyframe already
    torch.testing.assert_close(per_pixel["key_emb"], total["key_emb"] / 3)  # E = 3
    torch.testing.assert_close(per_pixel["kl"], total["kl"] / 4)  # Zk = 4
    torch.testing.assert_close(per_pixel["loss"], per_pixel["key"] + per_pixel["inter"])
    with pytest.raises(ValueError, match="needs latent_dim"):
        keyin_loss(**{**inputs, "latent_dim": None}, reduction="per_pixel")
    with pytest.raises(ValueError, match="reduction must be one of"):
        keyin_loss(**inputs, reduction="mean")


def test_stage_2_samples_a_stochastic_interpolator_from_its_prior():
    model = module(inter_latent=2).eval().model
    first, keys = torch.randn(3, 8), torch.randn(3, 3, 8)
    offsets = torch.softmax(torch.randn(3, 3, 3), -1)
    with torch.no_grad():
        torch.manual_seed(5)
        frames = model.interpolate(first, keys, offsets)
        torch.manual_seed(5)
        z = torch.randn(9, 2)  # what the prior draws
        starts = torch.cat([first[:, None], keys[:, :-1]], 1).flatten(0, 1)
        expected = torch.sigmoid(model.decoder(model.interpolator(starts, keys.flatten(0, 1), offsets.flatten(0, 1), z).flatten(0, 1)))
        again = model.interpolate(first, keys, offsets)
    torch.testing.assert_close(frames, expected.reshape(3, 3, 3, -1))
    assert not torch.allclose(frames, again)  # a new draw each time


def test_stage_1_samples_the_stochastic_interpolator_from_its_posterior():
    torch.manual_seed(0)
    stage1 = InterpolatorModule(**{**STAGE1, "latent_dim": 2})
    stage1.log = stage1.log_dict = lambda *args, **kwargs: None
    called = []
    forward = stage1.posterior.forward
    stage1.posterior.forward = lambda *args: called.append(1) or forward(*args)
    stage1.training_step(batch(), 0).backward()
    assert called and stage1.posterior.head.weight.grad.abs().sum() > 0


def test_the_entropy_aid_rewards_the_offsets_entropy_in_training_only():
    plain, aided = module(), module(entropy_bonus=2.0, entropy_bonus_steps=10)
    terms = {}
    for name, built in (("plain", plain), ("aided", aided)):
        for stage in ("train", "val"):
            terms[name, stage] = built._shared_step(batch(), stage)  # batch() seeds the latents' draw too
    data = batch()
    entropy = offset_entropy(plain.model(data["frames"], data["future_length"])["offset_probs"]).mean()
    torch.testing.assert_close(terms["aided", "train"]["loss"], terms["plain", "train"]["loss"] - 2.0 * entropy)  # step 0: full weight
    torch.testing.assert_close(terms["aided", "val"]["loss"], terms["plain", "val"]["loss"])
    with pytest.raises(ValueError, match="entropy_bonus"):
        module(entropy_bonus=1.0)


def test_a_stage_2_checkpoint_gives_its_frozen_stage_1():
    stage2 = load_checkpoint("pretrained:brownian")
    stage1 = load_stage1("pretrained:brownian")
    saved = torch.load(resolve("pretrained:brownian"), weights_only=True)["hyper_parameters"]["stage1"]  # flat, as saved
    assert stage1["hyper_parameters"] == {key: value for key, value in saved.items() if key in stage1["hyper_parameters"]}
    net = KEYINConfig.from_dict(stage2["hyper_parameters"]["net"])
    assert KEYINConfig.of_stage1(stage1["hyper_parameters"], net.predictor) == net
    interpolator = InterpolatorModule(**{**saved, **stage1["hyper_parameters"]})
    expected = {k for k in interpolator.state_dict() if k.startswith(("encoder.", "decoder.", "interpolator."))}
    assert set(stage1["state_dict"]) == expected
    for name, value in stage1["state_dict"].items():
        torch.testing.assert_close(value, stage2["state_dict"][f"model.{name}"])


def test_old_checkpoints_load_with_the_papers_choices_as_they_ran():
    module_, _ = load_trained_module("pretrained:brownian")
    assert module_.model.delta_input == "soft"
    loss = load_training_module("pretrained:brownian")[0].loss
    assert loss.reduction == "sum" and loss.entropy_bonus == 0.0


@pytest.mark.parametrize(
    ("frozen", "trained", "still"),
    [
        ("stage1", ("predictor",), ("encoder", "decoder", "interpolator")),
        ("interpolator", ("predictor", "encoder", "decoder"), ("interpolator",)),
        ("lstm_inter", ("predictor", "encoder", "decoder", "interpolator.init_mlp"), ("interpolator.lstm",)),
    ],
)
def test_stage_2_trains_what_it_does_not_freeze(frozen, trained, still):
    built = module(frozen=frozen).train()
    built._shared_step(batch(), "train")["loss"].backward()
    for name in trained:
        part = built.model.get_submodule(name)
        assert part.training and any(p.grad is not None and p.grad.abs().sum() > 0 for p in part.parameters()), name
    for name in still:
        part = built.model.get_submodule(name)
        assert not part.training and all(p.grad is None and not p.requires_grad for p in part.parameters()), name
    with pytest.raises(ValueError, match="frozen must be one of"):
        module(frozen="decoder")


def test_gumbel_offsets_sample_one_hot_offsets_in_training_and_keep_the_softmax_otherwise():
    built, data = module(gumbel_offsets=True), batch()
    model = built.train().model
    torch.manual_seed(0)
    out = model(data["frames"], data["future_length"])
    probs = out["offset_probs"]
    torch.testing.assert_close(probs.max(-1).values, torch.ones(3, 3))  # one-hot forward
    assert probs.requires_grad
    torch.testing.assert_close(probs.sum(-1), torch.ones(3, 3))
    draws = {tuple(model(data["frames"], data["future_length"])["offset_probs"].argmax(-1).flatten().tolist()) for _ in range(5)}
    assert len(draws) > 1  # a new sample each step
    with torch.no_grad():
        evaluated = model.eval()(data["frames"], data["future_length"], sample=False)
    torch.testing.assert_close(evaluated["offset_probs"], torch.softmax(evaluated["offset_logits"], -1))


def test_the_keyframe_image_term_scores_the_decoded_keyframes_against_the_soft_target_images():
    """β_ki > 0 (eq. 3's image term, 0 in the paper's runs): the loss grows by β_ki times the c-weighted mean
    BCE of sigmoid(CNN_dec(K̂^{e,t})) against K̃^t = Σ_j δ̃^t_j I_j / c^t, computed here clip by clip and
    keyframe by keyframe; the decoder stays frozen and the keyframe embeddings get the gradient."""
    plain, imaged = module(), module(beta_ki=0.5)
    data = batch()
    clips, lengths = data["frames"], data["future_length"]
    torch.manual_seed(3)
    out = imaged.model(clips, lengths, sample=False)
    with_image, without = imaged.soft_loss(clips, lengths, out), plain.soft_loss(clips, lengths, out)
    keyframe_pos, _ = position_distributions(out["offset_probs"])
    decoded = torch.sigmoid(imaged.model.decoder(out["key_emb"])).flatten(2)  # (B, M, D)
    future = clips[:, imaged.model.n_cond :].flatten(2)
    expected = []
    for b in range(len(clips)):
        inside = keyframe_pos[b, :, 1 : lengths[b] + 1]  # (M, n_b): P(keyframe t at frame j < n_b)
        c = inside.sum(-1)
        terms = []
        for t in range(out["key_emb"].shape[1]):
            target = (inside[t, :, None] * future[b, : lengths[b]]).sum(0) / c[t].clamp_min(1e-6)
            p = decoded[b, t].clamp(1e-6, 1 - 1e-6)
            terms.append(-(target * p.log() + (1 - target) * (1 - p).log()).sum())
        expected.append((c * torch.stack(terms)).sum() / c.sum())
    torch.testing.assert_close(with_image["loss"] - without["loss"], 0.5 * torch.stack(expected).mean(), rtol=1e-4, atol=1e-3)
    torch.testing.assert_close(with_image["key_img"], torch.stack(expected).mean(), rtol=1e-4, atol=1e-3)
    with_image["loss"].backward()
    assert all(p.grad is None for p in imaged.model.decoder.parameters())
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in imaged.model.predictor.parameters())
