"""KeyframePredictor and its Static / Jumpy offset modes (paper §3.1, §4 "Baselines")."""

import pytest
import torch

from keyin.models.attention import attention_posterior
from keyin.models.keyframe_predictor import KeyframePredictor

BATCH, COND, FRAMES = 3, 2, 12
EMBED_DIM, KEYFRAMES, MAX_OFFSET, LATENT_DIM, HIDDEN, LAYERS = 8, 4, 5, 3, 16, 2


def make_predictor(**kwargs) -> KeyframePredictor:
    torch.manual_seed(0)
    return KeyframePredictor(EMBED_DIM, KEYFRAMES, MAX_OFFSET, LATENT_DIM, HIDDEN, LAYERS, **kwargs)


def make_embeddings(seed: int = 1):
    generator = torch.Generator().manual_seed(seed)
    cond_emb = torch.rand(BATCH, COND, EMBED_DIM, generator=generator) * 2 - 1
    future_emb = torch.rand(BATCH, FRAMES, EMBED_DIM, generator=generator) * 2 - 1
    return cond_emb, future_emb


@pytest.mark.parametrize("mode", ["posterior", "prior"])
def test_output_shapes_and_offset_distributions(mode):
    predictor = make_predictor()
    cond_emb, future_emb = make_embeddings()

    output = predictor(cond_emb, future_emb, mode=mode)

    assert output.key_emb.shape == (BATCH, KEYFRAMES, EMBED_DIM)
    assert output.key_emb.abs().max() < 1
    assert output.offset_probs.shape == output.offset_logits.shape == (BATCH, KEYFRAMES, MAX_OFFSET)
    for latent in (output.mu, output.log_sigma, output.z):
        assert latent.shape == (BATCH, KEYFRAMES, LATENT_DIM)
    torch.testing.assert_close(output.offset_probs.sum(-1), torch.ones(BATCH, KEYFRAMES))
    torch.testing.assert_close(output.offset_probs, torch.softmax(output.offset_logits, -1))
    if mode == "posterior":
        assert output.attention.shape == (BATCH, KEYFRAMES, FRAMES)
        torch.testing.assert_close(output.attention.sum(-1), torch.ones(BATCH, KEYFRAMES))
    else:
        assert output.attention is None
        assert (output.mu == 0).all() and (output.log_sigma == 0).all()


def test_prior_mode_ignores_future_and_uses_given_z():
    predictor = make_predictor().eval()
    cond_emb, future_emb = make_embeddings()
    z = torch.randn(BATCH, KEYFRAMES, LATENT_DIM)

    without_future = predictor(cond_emb, None, mode="prior", z=z)
    with_future = predictor(cond_emb, future_emb, mode="prior", z=z)
    other_z = predictor(cond_emb, None, mode="prior", z=z + 1)

    torch.testing.assert_close(with_future, without_future)
    torch.testing.assert_close(without_future.z, z)
    assert not torch.allclose(other_z.key_emb, without_future.key_emb)
    assert not torch.allclose(other_z.offset_probs, without_future.offset_probs)


def test_a_prior_sample_is_reproduced_by_passing_its_z():
    # The latent CEM planner scores z it passes explicitly; they must give the sampled keyframes.
    predictor = make_predictor().eval()
    cond_emb, _ = make_embeddings()
    sampled = predictor(cond_emb, mode="prior", sample=True)
    torch.testing.assert_close(predictor(cond_emb, mode="prior", z=sampled.z), sampled, rtol=0, atol=0)


def test_prior_mode_samples_unless_told_not_to():
    predictor = make_predictor()
    cond_emb, _ = make_embeddings()

    first = predictor(cond_emb, mode="prior")
    second = predictor(cond_emb, mode="prior")
    mean = predictor(cond_emb, mode="prior", sample=False)

    assert not torch.allclose(first.z, second.z)
    assert (mean.z == 0).all()


def test_posterior_mean_is_deterministic_and_sampling_is_not():
    predictor = make_predictor()
    cond_emb, future_emb = make_embeddings()

    first = predictor(cond_emb, future_emb, sample=False)
    second = predictor(cond_emb, future_emb, sample=False)
    sampled = predictor(cond_emb, future_emb, sample=True)

    torch.testing.assert_close(first, second)
    torch.testing.assert_close(first.z, first.mu)
    assert not torch.allclose(sampled.z, sampled.mu)


def test_posterior_samples_are_reparameterised_with_sigma():
    predictor = make_predictor()
    with torch.no_grad():  # every frame's value is [μ = 0.5, log σ = log 0.05]
        predictor.inference_value_head.weight.zero_()
        predictor.inference_value_head.bias.copy_(torch.tensor([0.5] * LATENT_DIM + [-3.0] * LATENT_DIM))
    cond_emb, future_emb = make_embeddings()

    outputs = [predictor(cond_emb, future_emb) for _ in range(10)]
    noise = torch.stack([(output.z - output.mu) / output.log_sigma.exp() for output in outputs])

    torch.testing.assert_close(outputs[0].mu, torch.full_like(outputs[0].mu, 0.5))
    torch.testing.assert_close(outputs[0].log_sigma, torch.full_like(outputs[0].mu, -3.0))
    assert 0.8 < noise.std() < 1.2 and noise.mean().abs() < 0.2


def test_key_lstm_reads_latent_and_previous_keyframe():
    predictor = make_predictor()
    cond_emb, future_emb = make_embeddings()
    step_inputs = []
    predictor.key_lstm.input_projection.register_forward_hook(
        lambda module, args, output: step_inputs.append(args[0])
    )

    output = predictor(cond_emb, future_emb)

    previous_keys = torch.cat([cond_emb[:, -1:], output.key_emb[:, :-1]], dim=1)  # (B, M, E)
    expected = torch.cat([output.z, previous_keys], dim=-1)  # (B, M, Zk + E)
    torch.testing.assert_close(torch.cat(step_inputs, dim=1), expected)


def test_posterior_depends_on_future_and_conditioning_state():
    predictor = make_predictor()
    cond_emb, future_emb = make_embeddings()
    reference = predictor(cond_emb, future_emb, sample=False)

    other_future = predictor(cond_emb, -future_emb, sample=False)
    earlier_cond = cond_emb.clone()
    earlier_cond[:, 0] = -earlier_cond[:, 0]  # reaches LSTM_key only through Init_key = Final_cond
    other_cond = predictor(earlier_cond, future_emb, sample=False)

    assert not torch.allclose(other_future.mu, reference.mu)
    assert not torch.allclose(other_cond.key_emb, reference.key_emb)


def test_first_query_is_the_last_conditioning_embedding():
    """K^{e,0} = cond_emb[:, -1] queries the first keyframe's posterior; later queries are K̂^{e,t-1}."""
    predictor = make_predictor()
    cond_emb, future_emb = make_embeddings()

    output = predictor(cond_emb, future_emb, sample=False)
    keys, values, mask, _ = predictor.infer(future_emb, None)
    queries = torch.cat([cond_emb[:, -1:], output.key_emb[:, :-1]], dim=1)  # (B, M, E)

    for t in range(KEYFRAMES):
        mu, log_sigma, weights = attention_posterior(
            queries[:, t], keys, values, mask, predictor.attention_inv_temperature, True
        )
        torch.testing.assert_close(output.attention[:, t], weights)
        torch.testing.assert_close(output.mu[:, t], mu)
        torch.testing.assert_close(output.log_sigma[:, t], log_sigma)


def test_frames_beyond_lengths_are_masked_and_ignored():
    predictor = make_predictor()
    cond_emb, future_emb = make_embeddings()
    lengths = torch.tensor([FRAMES, 5, 0])

    output = predictor(cond_emb, future_emb, lengths, sample=False)
    padded = future_emb.clone()
    padded[1, 5:] = 5.0
    padded[2] = 5.0
    changed = predictor(cond_emb, padded, lengths, sample=False)

    valid = torch.arange(FRAMES) < lengths[:, None]
    assert (output.attention[~valid[:, None].expand(-1, KEYFRAMES, -1)] == 0).all()
    torch.testing.assert_close(output.attention[:2].sum(-1), torch.ones(2, KEYFRAMES))
    assert (output.mu[2] == 0).all() and (output.log_sigma[2] == 0).all()  # empty clip → prior
    torch.testing.assert_close(changed, output)
    full = predictor(cond_emb, future_emb, sample=False)
    torch.testing.assert_close(full.mu[0], output.mu[0])  # length N behaves like no lengths


def test_static_offsets_are_shared_by_all_sequences():
    predictor = make_predictor(offset_mode="static")
    with torch.no_grad():
        predictor.offset_head.logits.normal_()
    cond_emb, future_emb = make_embeddings()

    output = predictor(cond_emb, future_emb)
    other = predictor(-cond_emb, future_emb.flip(1))

    expected = torch.softmax(predictor.offset_head.logits, -1).expand(BATCH, -1, -1)
    torch.testing.assert_close(output.offset_probs, expected)
    torch.testing.assert_close(other.offset_probs, expected)
    assert [name for name, _ in predictor.offset_head.named_parameters()] == ["logits"]


@pytest.mark.parametrize("fixed_offset", [1, 3, MAX_OFFSET])
def test_fixed_offsets_are_one_hot(fixed_offset):
    predictor = make_predictor(offset_mode="fixed", fixed_offset=fixed_offset)
    cond_emb, future_emb = make_embeddings()

    output = predictor(cond_emb, future_emb)

    expected = torch.zeros(BATCH, KEYFRAMES, MAX_OFFSET)
    expected[..., fixed_offset - 1] = 1.0
    assert torch.equal(output.offset_probs, expected)
    assert torch.isfinite(torch.log_softmax(output.offset_logits, -1)).all()
    assert not list(predictor.offset_head.parameters())  # a fixed one-hot: nothing to learn


@pytest.mark.parametrize(
    "kwargs",
    [{}, {"attn_scale": False}, {"offset_mode": "static"}, {"offset_mode": "fixed", "fixed_offset": 2}],
)
def test_every_parameter_gets_a_gradient_in_posterior_mode(kwargs):
    """Unused parameters would break DDP and mean dead code."""
    predictor = make_predictor(**kwargs)
    cond_emb, future_emb = make_embeddings()

    output = predictor(cond_emb, future_emb)
    loss = output.key_emb.sum() + (output.offset_probs * torch.arange(MAX_OFFSET)).sum() + output.mu.sum()
    (loss + output.log_sigma.sum()).backward()

    missing = [name for name, param in predictor.named_parameters() if param.grad is None]
    assert missing == []
    assert (predictor.attention_inv_temperature is not None) == kwargs.get("attn_scale", True)


def test_invalid_arguments_raise():
    cond_emb, future_emb = make_embeddings()
    predictor = make_predictor()
    with pytest.raises(ValueError, match="future_emb"):
        predictor(cond_emb, None, mode="posterior")
    with pytest.raises(ValueError, match="prior mode"):
        predictor(cond_emb, future_emb, z=torch.zeros(BATCH, KEYFRAMES, LATENT_DIM))
    with pytest.raises(ValueError, match="shape"):
        predictor(cond_emb, mode="prior", z=torch.zeros(BATCH, KEYFRAMES + 1, LATENT_DIM))
    with pytest.raises(ValueError, match="mode"):
        predictor(cond_emb, future_emb, mode="inference")
    with pytest.raises(ValueError, match="fixed_offset"):
        make_predictor(offset_mode="fixed")
    with pytest.raises(ValueError, match="fixed_offset"):
        make_predictor(offset_mode="predicted", fixed_offset=2)
    with pytest.raises(ValueError, match="fixed_offset"):
        make_predictor(offset_mode="fixed", fixed_offset=MAX_OFFSET + 1)
    with pytest.raises(ValueError, match="offset_mode"):
        make_predictor(offset_mode="learned")


def test_boundary_evidence_points_each_keyframe_at_the_next_high_score():
    predictor = make_predictor(offset_evidence=True)
    n_future = 2 * MAX_OFFSET
    scores = torch.full((1, n_future), -20.0)
    scores[0, [2, 5]] = 20.0  # boundaries at positions 2 and 5
    mask = torch.ones(1, n_future, dtype=torch.bool)
    with torch.no_grad():
        predictor.beyond_score.fill_(-20.0)
        logits = predictor._add_boundary_evidence(torch.zeros(1, KEYFRAMES, MAX_OFFSET), scores, mask)
    offsets = logits.argmax(-1)[0] + 1
    assert offsets[:2].tolist() == [3, 3]  # position -1 → 2 → 5


def first_boundary_log_probs(boundary_logits: list[float], previous: int, max_offset: int) -> torch.Tensor:
    """Brute force: log P(the first boundary after extended index ``previous`` is at previous + a + 1)."""
    p = torch.sigmoid(torch.tensor(boundary_logits, dtype=torch.float64))
    out = []
    for a in range(max_offset):
        none_between = torch.prod(1 - p[previous + 1 : previous + a + 1])
        out.append(torch.log(p[previous + a + 1] * none_between))
    return torch.stack(out)


def test_boundary_evidence_is_the_first_boundary_log_probability():
    torch.manual_seed(0)
    predictor = make_predictor(offset_evidence=True)
    n_future = 2 * MAX_OFFSET
    scores = torch.randn(1, n_future) * 2
    mask = torch.ones(1, n_future, dtype=torch.bool)
    base = torch.randn(1, KEYFRAMES, MAX_OFFSET)
    with torch.no_grad():
        predictor.beyond_score.fill_(-1.5)
        logits = predictor._add_boundary_evidence(base, scores, mask)
    extended = [-1.5] + scores[0].tolist() + [-1.5] * (KEYFRAMES * MAX_OFFSET - n_future)
    # Keyframe 1 starts from K^0 (extended index 0) with certainty.
    expected = base[0, 0].double() + first_boundary_log_probs(extended, 0, MAX_OFFSET)
    torch.testing.assert_close(logits[0, 0].double(), expected, rtol=1e-5, atol=1e-5)


def test_the_argmax_chain_places_each_previous_keyframe_where_the_argmax_offsets_put_it():
    torch.manual_seed(2)
    predictor = make_predictor(offset_evidence=True)
    n_future = 2 * MAX_OFFSET
    scores, base = torch.randn(1, n_future) * 2, torch.randn(1, KEYFRAMES, MAX_OFFSET)
    mask = torch.ones(1, n_future, dtype=torch.bool)
    with torch.no_grad():
        predictor.beyond_score.fill_(-1.5)
        logits = predictor._add_boundary_evidence(base, scores, mask, chain="argmax")
        soft = predictor._add_boundary_evidence(base, scores, mask, chain="soft")
    extended = [-1.5] + scores[0].tolist() + [-1.5] * (KEYFRAMES * MAX_OFFSET - n_future)
    previous = 0  # extended index of K^0
    for t in range(KEYFRAMES):
        expected = base[0, t].double() + first_boundary_log_probs(extended, previous, MAX_OFFSET)
        torch.testing.assert_close(logits[0, t].double(), expected, rtol=1e-5, atol=1e-5)
        previous += int(logits[0, t].argmax()) + 1
    with torch.no_grad():  # the same path given as offsets (a teacher's) gives the same logits
        given = predictor._add_boundary_evidence(base, scores, mask, chain=logits.argmax(-1) + 1)
    torch.testing.assert_close(given, logits)
    torch.testing.assert_close(soft[0, 0], logits[0, 0])  # the first keyframe starts at K^0 either way
    assert not torch.allclose(soft[0, 1:], logits[0, 1:])
    with pytest.raises(ValueError, match="chain must be one of"):
        predictor(*make_embeddings(), chain="beam")


def test_boundary_evidence_does_not_skip_a_boundary_for_a_higher_later_score():
    predictor = make_predictor(offset_evidence=True)
    scores = torch.full((1, 2 * MAX_OFFSET), -20.0)
    scores[0, 0], scores[0, 1] = 3.0, 20.0  # a sure boundary at 0, a surer one right after
    mask = torch.ones_like(scores, dtype=torch.bool)
    with torch.no_grad():
        logits = predictor._add_boundary_evidence(torch.zeros(1, KEYFRAMES, MAX_OFFSET), scores, mask)
    assert logits.argmax(-1)[0, :2].tolist() == [0, 0]  # positions 0 then 1, not 1 first


def test_boundary_evidence_treats_padding_as_beyond_the_clip():
    predictor = make_predictor(offset_evidence=True)
    scores = torch.zeros(1, 2 * MAX_OFFSET)
    scores[0, 1] = 50.0  # a high score on a padded frame must not count
    mask = torch.zeros(1, 2 * MAX_OFFSET, dtype=torch.bool)
    mask[0, :1] = True
    with torch.no_grad():
        predictor.beyond_score.fill_(-3.0)
        logits = predictor._add_boundary_evidence(torch.zeros(1, KEYFRAMES, MAX_OFFSET), scores, mask)
    extended = [-3.0, 0.0] + [-3.0] * (KEYFRAMES * MAX_OFFSET - 1)
    torch.testing.assert_close(logits[0, 0].double(), first_boundary_log_probs(extended, 0, MAX_OFFSET))


def test_boundary_evidence_changes_posterior_offsets_only():
    torch.manual_seed(0)
    plain = make_predictor()
    with_evidence = make_predictor(offset_evidence=True)
    missing, unexpected = with_evidence.load_state_dict(plain.state_dict(), strict=False)
    assert set(missing) == {"boundary_head.weight", "boundary_head.bias", "beyond_score"} and not unexpected
    cond, future = torch.randn(2, 3, EMBED_DIM), torch.randn(2, 2 * MAX_OFFSET, EMBED_DIM)
    with torch.no_grad():
        with_evidence.boundary_head.bias.fill_(1.0)
        with_evidence.boundary_head.weight.normal_()
    assert not torch.allclose(with_evidence(cond, future, sample=False).offset_probs,
                              plain(cond, future, sample=False).offset_probs)
    torch.testing.assert_close(
        with_evidence(cond, mode="prior", sample=False).offset_probs,
        plain(cond, mode="prior", sample=False).offset_probs,
    )
    with pytest.raises(ValueError, match="offset_evidence"):
        make_predictor(offset_mode="static", offset_evidence=True)
