"""The paper's BatchNorm frame model: one decoder batch per training step (stage 1, Surprise's SVG), so that eval mode
(the running statistics) renders what training normalised (docs/decisions.md, "One decoder batch a step")."""

import torch

from keyin.data.segments import partition_segments

from tests.lit.tiny_models import batch, stage1, surprise, tap


def decoder_calls(module) -> list[tuple[torch.Tensor, torch.Tensor]]:
    """The (input, output) of every call of the module's decoder from now on."""
    calls = []
    module.decoder.register_forward_hook(lambda _, inputs, output: calls.append((inputs[0].detach(), output.detach())))
    return calls


def test_stage_1_decodes_the_interpolated_and_the_autoencoded_frames_in_one_batch():
    module = stage1("paper", latent_dim=2)
    module.log_dict = lambda *args, **kwargs: None
    calls = decoder_calls(module)
    clips = batch()
    draws = torch.Generator().set_state(module.segment_rng.get_state())  # the segments training_step will draw
    lengths = module.hparams.n_cond + clips["future_length"]
    n_interpolated = int(partition_segments(lengths, module.hparams.offset_min, module.hparams.offset_max, draws)[2].sum())
    module.training_step(clips, 0)
    assert [len(inputs) for inputs, _ in calls] == [n_interpolated + module.hparams.ae_frames]


def test_eval_mode_renders_what_a_batchnorm_stage_1_trained_on():
    module = stage1("paper", latent_dim=2)
    module.log_dict = lambda *args, **kwargs: None
    for layer in module.decoder.modules():
        if isinstance(layer, torch.nn.BatchNorm2d):
            layer.momentum = 1.0  # the running statistics: those of the last training batch
    calls = decoder_calls(module)
    module.train()
    with torch.no_grad():
        module.training_step(batch(), 0)
    module.eval()
    for inputs, trained in calls[:]:
        torch.testing.assert_close(module.decoder(inputs), trained, rtol=0.02, atol=0.02)


def test_surprise_decodes_its_predictions_and_its_autoencoded_frames_in_one_batch():
    module = surprise()
    module.model.decoder = type(module.model.decoder)(8, 1, 4, 8, norm="batch")  # the paper's frame model: BatchNorm
    calls = decoder_calls(module.model)
    clips = batch()["frames"]
    out = module.model(clips, sample=False, reconstruct=True)
    assert len(calls) == 1 and out.logits.shape[1] == clips.shape[1] - 1 and out.reconstruction.shape == clips.shape
    module.model.eval()
    alone = module.model(clips, sample=False, reconstruct=False)  # eval mode: per-frame, so the split is exact
    together = module.model(clips, sample=False, reconstruct=True)
    torch.testing.assert_close(together.logits, alone.logits)


def test_tap_decodes_its_prediction_and_its_autoencoded_pair_in_one_batch():
    module = tap(norm="batch")
    module.log_dict = lambda *args, **kwargs: None
    calls = decoder_calls(module.network)
    clips = batch()
    module.training_step(clips, 0)
    assert [len(inputs) for inputs, _ in calls] == [3 * len(clips["frames"])]  # a prediction, a start and a goal a clip
