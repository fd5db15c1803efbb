"""Which channel of the keyframe predictor walks away from the true keyframes under the paper's loss? (issue 62)

    python studies/warm_start_arms.py pretrained:brownian --arms sampled mean tied_mean --steps 500 \
        --out docs/results/warm_start_brownian/arms.md

Every arm starts stage 2 at the same trained checkpoint (``pretrained:brownian``: keyin_plus, argmax-offset
F1 0.872 on 300 validation clips), drops the teacher, and trains on the paper's loss (eq. 3-5 as keyin
implements it, ``KeyframeModule.soft_loss``) with a fresh Adam, the same training clips and seed;
every ``--every`` steps it scores the argmax offsets (keyin-eval's ``offsets`` rule) on ``--clips``
validation clips and logs each term of the loss there. The arms change one channel at a time:

- ``sampled``: as keyin-train trains (the keyframe latents z drawn from the posterior);
- ``mean``: z at its posterior mean (no sampling noise in δ and K̂);
- ``tied_mean``: z at its mean and K̂ replaced by its soft target K̃^e(δ) (the keyframes follow δ exactly;
  L_ke = 0), so δ is the only thing that moves the interpolation;
- ``tied_interpolator``: z sampled; the interpolator reads K̃^e(δ) (the embeddings of the frames δ points at)
  instead of the predicted K̂, which L_ke still trains (the prior's keyframes for planning stay learned);
- ``beta_ke100`` / ``beta_ke1000``: the paper's loss with β_ke = 100 / 1000 (K̂ held to its frames harder);
- ``scratch_*``: not a warm start: a fresh keyin_paper predictor on the checkpoint's stage 1, the interpolator reading
  K̃^e(δ), with aids that keep δ from saturating: the offset head initialised to zero (``_uniform``), its logits' temperature
  annealed from 10 to 1 over 1000 steps (``_anneal``), its learning rate a tenth of the rest's (``_slow``), the keyframe
  KL's weight 0 so that nothing pulls the latents to the prior (``_kl0``);
- ``placed``: not a warm start from a trained stage 2: a fresh predictor (``--scratch-overrides``, e.g. the stated
  configuration's ``experiment=brownian_keyin_stated``) on the checkpoint's stage 1, its first 300 steps the paper's loss plus
  100 × the cross-entropy of δ^t at the labelled offsets (labels only place the start), then the paper's loss alone;
- ``placed_supervised``: as ``placed``, but the placement trains on the labels alone (100 × the cross-entropy of δ^t at the
  labelled offsets, with L_ke and the KL, without L_inter) at lr 1e-3 until the validation F1 has not risen for five
  validations (at most 1500 steps), then 500 steps of the paper's loss alone at the stated lr 2e-4 with a fresh Adam;
- ``placed_supervised_1500``: as ``placed_supervised`` with a fixed placement of 1500 steps (no stopping rule: on the labels
  alone the paper's predictor sits at the offsets' marginal for its first ~500 steps at lr 1e-3, which the rule would take
  for the end; studies/supervised_offsets.py), then 500 steps of the paper's loss alone;
- ``sampled_lr1e-4`` / ``mean_lr1e-4``: the same at a tenth of the learning rate;
- ``expected``: as ``sampled``, but L_inter scores each interpolated frame against the frame it may land on,
  weighted by that probability (Σ δ̃ BCE(I_j, Î_i), not the paper's BCE(I_j, Σ δ̃ Î_i)): hedging over
  alignments no longer lowers the loss (studies/paper_loss_truth.py, reading ``expected_bce``).
"""

from __future__ import annotations

import argparse
import json
import dataclasses
from dataclasses import dataclass
import sys
import time
from datetime import date
from pathlib import Path

import torch
from torch.utils.data import DataLoader

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from paper_loss_truth import Clips, Reading, interpolation_term  # noqa: E402
from stage2_diagnostics import true_offsets  # noqa: E402

from keyin.checkpoints import load_checkpoint  # noqa: E402
from keyin.data.datamodule import split_clips  # noqa: E402
from keyin.eval.f1 import keyframe_lists, keyframe_scores  # noqa: E402
from keyin.lit.registry import load_training_module, run_config  # noqa: E402
from keyin.models.modes import evaluating  # noqa: E402
from keyin.losses.soft_keyframe import offset_entropy  # noqa: E402
from keyin.models.positions import position_distributions, soft_keyframe_targets  # noqa: E402
from hydra.utils import instantiate  # noqa: E402

@dataclass(frozen=True)
class Arm:
    sample: bool = True  # z drawn from the posterior (False: its mean)
    tie: str = "none"  # none | interpolator: it reads K̃^e(δ), L_ke still trains K̂ | all: K̂ := K̃^e(δ), L_ke = 0
    lr: float = 1e-3
    expected: bool = False  # L_inter as the expected BCE over where each frame lands
    beta_ke: float | None = None  # None: the checkpoint's β_ke (1)
    beta_kl: float | None = None  # None: the checkpoint's β (0.05)
    # from scratch: a fresh keyin_paper predictor (backbone=ours, scale=cpu) on the checkpoint's stage 1, and aids against
    # δ saturating before the clips' information reaches it (issue 62, item 3)
    scratch: bool = False
    uniform_init: bool = False  # the offset head starts at zero: δ uniform for every clip
    temperature: float = 1.0  # offset logits divided by T, annealed linearly from this to 1 over anneal_steps
    anneal_steps: int = 1000
    offset_lr_scale: float = 1.0  # the offset head's learning rate, a fraction of the rest's
    # labels only place the start (issue 62, item 2): the first place_steps steps add place_weight times the cross-entropy
    # of δ^t against the labelled offsets to the paper's loss; after them, the paper's loss alone
    place_steps: int = 0  # at most, with place_patience
    place_weight: float = 100.0
    place_inter: bool = True  # False: the placement drops L_inter (labels, L_ke and the KL only)
    place_lr: float | None = None  # None: lr throughout, one Adam; else the placement's lr, and a fresh Adam at lr after it
    place_patience: int = 0  # > 0: the placement ends once the validation F1 has not risen for this many validations
    release_steps: int = 0  # > 0: the paper's loss alone for this many steps after the placement (instead of --steps)


ARMS = {
    "sampled": Arm(),
    "mean": Arm(sample=False),
    "tied_mean": Arm(sample=False, tie="all"),
    "tied_interpolator": Arm(tie="interpolator"),
    "sampled_lr1e-4": Arm(lr=1e-4),
    "mean_lr1e-4": Arm(sample=False, lr=1e-4),
    "expected": Arm(expected=True),
    "beta_ke100": Arm(beta_ke=100.0),
    "beta_ke1000": Arm(beta_ke=1000.0),
    "scratch_frames": Arm(scratch=True, tie="interpolator"),
    "scratch_frames_uniform": Arm(scratch=True, tie="interpolator", uniform_init=True),
    "scratch_frames_anneal": Arm(scratch=True, tie="interpolator", uniform_init=True, temperature=10.0),
    "scratch_frames_slow": Arm(scratch=True, tie="interpolator", uniform_init=True, offset_lr_scale=0.1),
    "scratch_frames_kl0": Arm(scratch=True, tie="interpolator", uniform_init=True, beta_kl=0.0),
    # a fresh predictor (--scratch-overrides: the stated configuration's) placed at the labelled offsets, then the paper's loss
    "placed": Arm(scratch=True, place_steps=300, lr=2e-4),
    "placed_supervised": Arm(scratch=True, place_steps=1500, lr=2e-4, place_inter=False, place_lr=1e-3, place_patience=5,
                             release_steps=500),
    "placed_supervised_1500": Arm(scratch=True, place_steps=1500, lr=2e-4, place_inter=False, place_lr=1e-3, release_steps=500),
}
SCRATCH_OVERRIDES = ["model=keyin_paper", "backbone=ours", "scale=cpu"]  # the Table 1 rows' keyin_paper


def scratch_module(ckpt: str, overrides: list[str]):
    """A fresh stage 2 composed by keyin-train's ``overrides`` (:data:`SCRATCH_OVERRIDES`; the stated configuration:
    ``experiment=brownian_keyin_stated``) on ``ckpt``'s stage 1."""
    from hydra import compose, initialize_config_module

    from keyin.checkpoints import load_stage1
    from keyin.cli.app import CONFIG_MODULE

    stage1 = load_stage1(ckpt)
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose("train", overrides=overrides)
    module = instantiate(cfg.model.keyframes, stage1=stage1["hyper_parameters"])
    module.load_stage1(stage1["state_dict"])
    return module


def placement_loss(offset_probs: torch.Tensor, keyframes: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
    """() the mean over clips of Σ_t −log δ^t at the labelled offsets (then the one leaving the clip, the rest S).

    Args:
        offset_probs: (B, M, S) δ; keyframes: (B, N) bool labels; lengths: (B,) valid future frames.
    """
    n_keyframes, max_offset = offset_probs.shape[1:]
    truth = true_offsets(keyframes, lengths, n_keyframes, max_offset).to(offset_probs.device)  # (B, M) in 1..S
    picked = offset_probs.gather(-1, (truth - 1)[..., None]).squeeze(-1)  # (B, M)
    return -picked.clamp_min(1e-12).log().sum(-1).mean()


def placement_over(f1s: list[float], patience: int) -> bool:
    """Whether a placement whose validation F1 so far is ``f1s`` (from its first validation after step 0) ends: the last
    ``patience`` validations did not beat the best before them."""
    return 0 < patience < len(f1s) and max(f1s[-patience:]) <= max(f1s[:-patience])


def temperature_at(arm: Arm, step: int) -> float:
    """The offset logits' temperature at ``step``: ``arm.temperature`` falling linearly to 1."""
    return 1.0 + (arm.temperature - 1.0) * max(0.0, 1.0 - step / arm.anneal_steps)
EXPECTED = Reading("expected_bce", "Σ δ̃ BCE(I_j, Î_i)", mixture="expected")


def expected_inter(module, clips: torch.Tensor, lengths: torch.Tensor, out: dict) -> torch.Tensor:
    """(B,) L_inter as the expected BCE of the interpolated frames over where they land."""
    _, frame_pos = position_distributions(out["offset_probs"])
    future = clips[:, module.model.n_cond :].flatten(2)
    return interpolation_term(EXPECTED, frame_pos, out["frames"], Clips(None, None, None, future, lengths, []))


def arm_loss(module, clips: torch.Tensor, lengths: torch.Tensor, out: dict, expected: bool) -> dict[str, torch.Tensor]:
    """The paper's loss terms of ``out``; with ``expected`` its L_inter replaced by :func:`expected_inter`."""
    terms = module.soft_loss(clips, lengths, out)
    terms["inter_expected"] = expected_inter(module, clips, lengths, out).mean()
    if expected:
        terms["loss"] = terms["loss"] - terms["inter"] + terms["inter_expected"]
    return terms


def forward(module, clips: torch.Tensor, lengths: torch.Tensor, arm: Arm) -> dict:
    """The posterior forward of ``KEYIN.forward``, with the latents' mean when not ``arm.sample`` and the
    interpolator reading K̃^e(δ) where ``arm.tie`` says so."""
    model = module.model
    model.interpolate_from = "predicted" if arm.tie == "none" else "frames"  # keyin's option (models/keyin.py)
    out = model(clips, lengths, sample=arm.sample)
    if arm.tie == "all":
        keyframe_pos, _ = position_distributions(out["offset_probs"])
        out["key_emb"] = soft_keyframe_targets(keyframe_pos, lengths, out["future_emb"], normalize=True)
    return out


@torch.no_grad()
def offset_scores(module, batch: dict) -> dict[str, float]:
    """The argmax offsets (keyin-eval's ``offsets``) on the batch: F1, interior keyframes per clip, distinct patterns."""
    clips = batch["frames"]
    found = module.reader().discover(clips, batch["future_length"], "offsets")
    scores = keyframe_scores(found, keyframe_lists(batch["keyframes"]), clips.shape[1] - module.model.n_cond)
    return {"f1": scores["f1"], "keys": scores["n_predicted"], "patterns": float(len({tuple(row) for row in found}))}


@torch.no_grad()
def validate(module, batch: dict, arm: Arm) -> dict[str, float]:
    """Argmax-offset F1 (keyin-eval's ``offsets``) and the loss terms on the validation batch."""
    clips, lengths = batch["frames"], batch["future_length"]
    offsets = offset_scores(module, batch)
    with evaluating(module):
        torch.manual_seed(0)
        out = forward(module, clips, lengths, arm)
        terms = arm_loss(module, clips, lengths, out, arm.expected)
    return {
        **offsets, "loss": terms["loss"].item(), "inter": terms["inter"].item(), "key_emb": terms["key_emb"].item(),
        "kl": terms["kl"].item(), "entropy": offset_entropy(out["offset_probs"]).mean().item(),
        "inter_expected": terms["inter_expected"].item(),
    }


def run_arm(ckpt: str, arm: str, train, val_batch: dict, steps: int, every: int, batch_size: int, seed: int,
            scratch_overrides: list[str] = SCRATCH_OVERRIDES) -> list[dict]:
    spec = ARMS[arm]
    torch.manual_seed(seed)
    module = scratch_module(ckpt, scratch_overrides) if spec.scratch else load_training_module(ckpt)[0]
    if spec.beta_ke is not None:
        module.loss = dataclasses.replace(module.loss, beta_ke=spec.beta_ke)
    if spec.beta_kl is not None:
        module.loss = dataclasses.replace(module.loss, beta_kl=spec.beta_kl)
    head = module.model.predictor.offset_head
    if spec.uniform_init:
        torch.nn.init.zeros_(head.weight)
        torch.nn.init.zeros_(head.bias)
    temperature = [temperature_at(spec, 0)]
    head.register_forward_hook(lambda _module, _inputs, logits: logits / temperature[0])
    module.train()
    head_params = {id(p) for p in head.parameters()}
    trainable = [p for p in module.parameters() if p.requires_grad]

    def adam(lr: float) -> torch.optim.Optimizer:
        return torch.optim.Adam([
            {"params": [p for p in trainable if id(p) not in head_params]},
            {"params": [p for p in trainable if id(p) in head_params], "lr": lr * spec.offset_lr_scale},
        ], lr=lr, betas=(0.9, 0.999))

    optimizer = adam(spec.place_lr if spec.place_steps and spec.place_lr else spec.lr)
    generator = torch.Generator().manual_seed(seed)
    loader = iter(DataLoader(train, batch_size=batch_size, shuffle=True, generator=generator, drop_last=True))
    torch.manual_seed(seed)
    rows = [{"step": 0, "phase": "placed" if spec.place_steps else "free", **validate(module, val_batch, spec)}]
    print(arm, rows[-1], flush=True)
    placed_until, last = spec.place_steps, steps
    step = 0
    while step < last:
        step += 1
        placing = step <= placed_until
        temperature[0] = temperature_at(spec, step)
        batch = next(loader)
        module.train()
        out = forward(module, batch["frames"], batch["future_length"], spec)
        terms = arm_loss(module, batch["frames"], batch["future_length"], out, spec.expected)
        loss = terms["loss"]
        if placing:  # labels place the start, then the paper's loss alone
            if not spec.place_inter:
                loss = loss - terms["inter_expected" if spec.expected else "inter"]
            loss = loss + spec.place_weight * placement_loss(out["offset_probs"], batch["keyframes"], batch["future_length"])
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        if step % every == 0:
            rows.append({"step": step, "phase": "placed" if placing else "free", **validate(module, val_batch, spec)})
            print(arm, rows[-1], flush=True)
            placed_f1s = [row["f1"] for row in rows[1:] if row["phase"] == "placed"]  # the untrained start aside
            if placing and (step == placed_until or placement_over(placed_f1s, spec.place_patience)):
                placed_until = step
                if spec.release_steps:
                    last = step + spec.release_steps
                if spec.place_lr:
                    optimizer = adam(spec.lr)
    return rows


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=300)
    parser.add_argument("ckpt", help="a stage-2 checkpoint or pretrained:<name> to start every arm at")
    parser.add_argument("--arms", nargs="+", default=list(ARMS), choices=list(ARMS))
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--every", type=int, default=100)
    parser.add_argument("--batch-size", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--scratch-overrides", nargs="+", default=SCRATCH_OVERRIDES,
                        help="keyin-train overrides of the fresh predictor of the scratch arms (e.g. experiment=brownian_keyin_stated)")
    args = parser.parse_args()
    config = run_config(load_checkpoint(args.ckpt, None))  # a stage-2 checkpoint, or for the scratch arms a stage-1 one
    dataset, val_batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    train = split_clips(dataset, instantiate(dataset.generator), "train", 100_000, args.data_dir)
    started = time.perf_counter()
    results = {}
    for arm in args.arms:
        results[arm] = run_arm(args.ckpt, arm, train, val_batch, args.steps, args.every, args.batch_size, args.seed,
                               args.scratch_overrides)
        if args.json:  # after each arm: a stopped run keeps what it measured
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({"date": str(date.today()), **results}, indent=1))
    minutes = (time.perf_counter() - started) / 60
    command = (f"python studies/warm_start_arms.py {args.ckpt} --arms {' '.join(args.arms)} --steps {args.steps} "
               f"--every {args.every} --clips {args.clips} --seed {args.seed}"
               + (f" --scratch-overrides {' '.join(args.scratch_overrides)}" if args.scratch_overrides != SCRATCH_OVERRIDES else ""))
    lines = [
        f"# Warm start at `{args.ckpt}` on the paper's loss alone, one channel changed per arm",
        "",
        f"`{command}` ({len(val_batch['frames'])} {args.split} clips; {cpu_model()}, {torch.get_num_threads()} thread(s), "
        f"{date.today()}, {minutes:.0f} min). Columns: argmax-offset F1, interior keyframes per clip, distinct patterns, "
        "the loss and its terms (nats per clip) and δ's entropy on the validation clips.",
        "",
        "| arm | step | phase | F1 | keys/clip | patterns | loss | L_inter | L_inter, expected error | L_ke | KL | δ entropy |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for arm, rows in results.items():
        lines += [f"| {arm} | {r['step']} | {r['phase']} | {r['f1']:.3f} | {r['keys']:.2f} | {r['patterns']:.0f} | {r['loss']:.1f} | "
                  f"{r['inter']:.1f} | {r['inter_expected']:.1f} | {r['key_emb']:.2f} | {r['kl']:.1f} | {r['entropy']:.2f} |" for r in rows]
    publish("\n".join(lines) + "\n", args.out)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"command": command, "date": str(date.today()), **results}, indent=1))


if __name__ == "__main__":
    main()
