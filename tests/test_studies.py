"""The studies' own maths (studies/): what a study computes that keyin does not, checked as keyin's maths is."""

import itertools
import math
import sys
from pathlib import Path

import pytest
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from readout_chain import joint_offset_keyframes, offset_log_probs  # noqa: E402
from warm_start_arms import placement_loss, placement_over  # noqa: E402
from stage1_latent_use import latent_use  # noqa: E402
from supervised_offsets import PARTS, gradient_norms  # noqa: E402
from training_curves import validation_rows  # noqa: E402
from warm_start_curves import arm_rows  # noqa: E402


def brute_force_joint(log_offsets: torch.Tensor, length: int) -> list[int]:
    """Every offset sequence: the best sum of log δ up to the first keyframe that leaves (or M)."""
    n_keys, _, max_offset = log_offsets.shape
    best, best_places = -float("inf"), []
    for offsets in itertools.product(range(1, max_offset + 1), repeat=n_keys):
        place, total, places = 0, 0.0, []
        for t, offset in enumerate(offsets):
            total += float(log_offsets[t, place, offset - 1])
            place += offset
            places.append(place)
            if place > length:
                break
        if total > best + 1e-9:
            best, best_places = total, [p - 1 for p in places if p <= length]
    return best_places


def test_the_joint_readout_is_the_most_likely_offset_path():
    torch.manual_seed(0)
    n_keys, max_offset = 3, 3
    log_offsets = torch.log_softmax(torch.randn(5, n_keys, n_keys * max_offset + 1, max_offset) * 2, -1)
    lengths = torch.tensor([4, 7, 9, 2, 5])
    found = joint_offset_keyframes(log_offsets, lengths)
    assert found == [brute_force_joint(log_offsets[b], int(lengths[b])) for b in range(5)]


def test_the_placement_ends_when_the_f1_has_not_risen_for_patience_validations():
    assert not placement_over([0.1, 0.3, 0.5], 2)
    assert not placement_over([0.1, 0.5, 0.4], 2)  # one validation without a rise
    assert placement_over([0.1, 0.5, 0.4, 0.5], 2)  # equal to the best is no rise
    assert not placement_over([0.1, 0.5, 0.4, 0.6], 2)
    assert not placement_over([0.1, 0.2, 0.1, 0.1], 0)  # no patience: only the step budget ends it
    assert not placement_over([0.1, 0.1], 2)  # too few validations to judge


def test_offset_log_probs_along_a_path_are_the_chains_logits():
    from tests.planning.trained_models import keyframe_module

    model = keyframe_module(offset_evidence=True).model.eval()
    with torch.no_grad():
        model.predictor.boundary_head.bias.fill_(0.5)
        clips, lengths = torch.rand(2, 7, 3, 16, 16), torch.tensor([6, 4])
        head = []  # the offset head's own logits, as the study reads them
        hook = model.predictor.offset_head.register_forward_hook(lambda _module, _inputs, logits: head.append(logits))
        _, keys = model.keyframes(clips, lengths, sample=False, chain="argmax")
        hook.remove()
        table = offset_log_probs(model.predictor, head[0], keys.boundary_scores, torch.arange(6) < lengths[:, None])
    place = torch.zeros(2, dtype=torch.long)
    for t in range(keys.offset_logits.shape[1]):  # the argmax chain visits one row of the table per keyframe
        expected = torch.log_softmax(keys.offset_logits[:, t], -1)
        torch.testing.assert_close(table[torch.arange(2), t, place], expected, rtol=1e-5, atol=1e-5)
        place = place + keys.offset_logits[:, t].argmax(-1) + 1


def test_the_placement_loss_is_the_cross_entropy_of_delta_at_the_labelled_offsets():
    # one clip of N = 8 future frames, keyframes at 2 and 5: offsets 3, 3, then 3 to leave the clip (frame 8), the rest S = 4
    keyframes = torch.zeros(1, 8, dtype=torch.bool)
    keyframes[0, [2, 5]] = True
    probs = torch.full((1, 4, 4), 0.1)
    probs[0, :, 2] = 0.7  # offset 3 at 0.7 in every slot
    expected = -(3 * math.log(0.7) + math.log(0.1))  # slots 1-3 at offset 3, slot 4 at offset S = 4
    torch.testing.assert_close(placement_loss(probs, keyframes, torch.tensor([8])), torch.tensor(expected))


def test_latent_use_leaves_batchnorm_as_it_was_and_a_deterministic_interpolator_ignores_the_latent():
    from tests.lit import tiny_models

    stochastic, deterministic = tiny_models.stage1("paper", latent_dim=2), tiny_models.stage1("paper", latent_dim=0)
    stochastic.train(False)
    before = {name: buffer.clone() for name, buffer in stochastic.named_buffers()}
    row = latent_use(stochastic, tiny_models.batch())
    assert all(torch.equal(buffer, before[name]) for name, buffer in stochastic.named_buffers())
    assert not stochastic.training
    assert row["train_kl"] > 0 and row["train_posterior"] != row["train_prior"]
    row = latent_use(deterministic, tiny_models.batch())
    for mode in ("train", "eval", "decoder_train"):
        assert row[f"{mode}_posterior"] == row[f"{mode}_prior"] == row[f"{mode}_mean"]
        assert row[f"{mode}_kl"] == 0
    assert row["eval_posterior"] != row["train_posterior"]  # BatchNorm: running against batch statistics


def test_gradient_norms_sum_each_parts_squared_gradients_and_leave_other_parameters_out():
    predictor = torch.nn.ModuleDict({
        "cond_lstm": torch.nn.Linear(2, 2), "inference_lstm": torch.nn.Linear(2, 1), "inference_key_head": torch.nn.Linear(2, 1),
        "key_lstm": torch.nn.Linear(2, 1), "offset_head": torch.nn.Linear(2, 3), "unrelated": torch.nn.Linear(2, 2),
    })
    for parameter in predictor.parameters():
        parameter.grad = torch.full_like(parameter, 2.0)
    predictor["key_lstm"].weight.grad = None  # a part with a parameter no gradient reached
    norms = gradient_norms(predictor)
    assert set(norms) == set(PARTS)
    assert math.isclose(norms["LSTM_cond"], 2.0 * math.sqrt(4 + 2))  # weight (2, 2) and bias (2,)
    assert math.isclose(norms["LSTM_inf + attention"], 2.0 * math.sqrt(2 * (2 + 1)))  # two heads of 2 + 1 numbers
    assert math.isclose(norms["LSTM_key + K̂ head"], 2.0)  # its bias alone
    assert math.isclose(norms["offset head"], 2.0 * math.sqrt(6 + 3))


def test_validation_rows_read_a_run_dirs_versions_in_the_order_they_ran_or_one_committed_csv(tmp_path):
    header = "step,val/f1,val/distinct_patterns,val/offset_entropy,train/loss\n"
    for version, text in ((2, "999,0.1,3,0.5,\n1999,0.2,4,0.4,\n10,,,,7.0\n"), (10, "1999,0.3,5,0.3,\n2999,0.4,6,0.2,\n")):
        folder = tmp_path / "run" / "csv" / f"version_{version}"
        folder.mkdir(parents=True)
        (folder / "metrics.csv").write_text(header + text)
    rows = validation_rows(tmp_path / "run")
    assert [(row["step"], row["val/f1"]) for row in rows] == [(999, 0.1), (1999, 0.3), (2999, 0.4)]  # version 10 last
    (tmp_path / "record.csv").write_text(header + "999,0.5,2,0.1,\n5,,,,3.0\n")
    assert validation_rows(tmp_path / "record.csv") == [
        {"step": 999, "val/f1": 0.5, "val/distinct_patterns": 2.0, "val/offset_entropy": 0.1}
    ]


def test_arm_rows_read_one_arm_of_a_studys_json_and_name_the_arms_there_are(tmp_path):
    study = tmp_path / "arms.json"
    study.write_text('{"command": "python studies/warm_start_arms.py", "sampled": [{"step": 0, "f1": 0.87}]}')
    assert arm_rows(f"{study}:sampled") == [{"step": 0, "f1": 0.87}]
    with pytest.raises(SystemExit, match=r"has no arm 'tied'; it has \['sampled'\]"):
        arm_rows(f"{study}:tied")
