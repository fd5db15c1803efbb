"""KEYIN's discovery rules as objects (keyin/decode/registry.py): every registered rule against a
brute-force reference on a small stage-2 model, what each declares it reads, and that no module
but the registry names a rule."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from keyin.decode.prices import Prices
from keyin.decode.registry import RULES, fastest_rule, model_rule, rule_named
from keyin.decode.rules import read_posterior
from keyin.decode.segment_costs import interpolation_costs
from tests.decode.enumeration import cheapest_keyframes, keyframe_sets
from tests.planning.trained_models import keyframe_module

PACKAGE = Path(__file__).parents[2] / "keyin"
PRICES = Prices(keyframe_cost=1.0, boundary_weight=0.3)
# Homonyms: string constants that spell a rule's name but mean something else.
HOMONYMS = {(where, "boundaries") for where in ("models/interpolator.py", "models/config.py")}  # stage 1's step input


def offsets_reference(read, row, bce, length, prices):
    """The argmax offsets' positions, Σ_{i≤m} (argmax δ_i + 1) - 1, inside the clip."""
    return [p for p in ((read.keys.offset_probs[row].argmax(-1) + 1).cumsum(0) - 1).tolist() if p < length]


def cheapest_set(read, row, bce, length, price, weight, candidates=None):
    """The keyframe set of least summed segment ``bce`` (N, S) + ``price`` per gap − ``weight`` · boundary
    scores by enumeration, among ``candidates`` (N,) bool (every set where none cuts the clip)."""
    predictor, scores = read.model.predictor, read.keys.boundary_scores[row]
    sets = keyframe_sets(length, predictor.max_offset, predictor.n_keyframes)
    inside = [chosen for chosen in sets if candidates is None or all(candidates[p] for p in chosen)]
    return cheapest_keyframes(bce, scores, inside or sets, length, price, weight)


REFERENCES = {  # rule name -> (read, row, (N, S) segment BCE, valid length, prices) -> the row's interior keyframes
    "offsets": offsets_reference,
    "boundaries": lambda read, row, bce, length, prices: cheapest_set(read, row, torch.zeros_like(bce), length, 0.0, 1.0),
    "map": lambda read, row, bce, length, prices: cheapest_set(
        read, row, bce, length, prices.keyframe_cost, prices.boundary_weight),
    "map_pruned": lambda read, row, bce, length, prices: cheapest_set(
        read, row, bce, length, prices.keyframe_cost, prices.boundary_weight,
        read.keys.boundary_scores[row] >= prices.candidate_logit),
    "segmentation": lambda read, row, bce, length, prices: cheapest_set(read, row, bce, length, prices.keyframe_cost, 0.0),
}


def test_every_registered_rule_has_a_reference_here():
    assert set(REFERENCES) == set(RULES)


def test_the_references_premise_the_rules_disagree_on_these_clips(stage2):
    module, clips, lengths, read, _ = stage2
    prices = Prices(PRICES.keyframe_cost, PRICES.boundary_weight, float(read.keys.boundary_scores.median()))
    assert len({repr(rule(module.model, clips, lengths, prices)) for rule in RULES.values()}) == len(RULES)


@pytest.fixture(scope="module")
def stage2():
    """A small stage 2 with offset evidence (n_cond 1, N 6, M 3, S 3) whose boundary logits spread
    over about -4 … 5, its clips, their posterior read and every segment's interpolation BCE."""
    module = keyframe_module(offset_evidence=True, map_boundary_weight=PRICES.boundary_weight).eval()
    head = module.model.predictor.boundary_head
    torch.nn.init.normal_(head.weight, std=40.0, generator=torch.Generator().manual_seed(0))
    torch.nn.init.constant_(head.bias, 7.5)
    torch.manual_seed(4)
    clips, lengths = (torch.rand(6, 7, 3, 16, 16) > 0.5).float(), torch.tensor([6, 6, 6, 5, 4, 6])
    with torch.no_grad():
        read = read_posterior(module.model, clips, lengths)
        n_cond = module.model.n_cond
        bce = interpolation_costs(module.model.interpolator, module.model.decoder, read.embeddings[:, n_cond - 1 :],
                                  clips[:, n_cond:].flatten(2))
    return module, clips, lengths, read, bce


@pytest.mark.parametrize("name", RULES)
def test_each_rule_finds_the_keyframes_of_its_brute_force_reference(stage2, name):
    module, clips, lengths, read, bce = stage2
    rule = RULES[name]
    prices = Prices(PRICES.keyframe_cost, PRICES.boundary_weight, float(read.keys.boundary_scores.median()))
    found = rule(module.model, clips, lengths, prices)
    for row, length in enumerate(lengths.tolist()):
        expected = REFERENCES[name](read, row, bce[row], length, prices)
        if rule.adds_sequence_ends and length < clips.shape[1] - module.model.n_cond:
            expected = [*expected, length - 1]
        assert found[row] == expected, row
    assert module.reader().discover(clips, lengths, name, PRICES.keyframe_cost, candidate_logit=prices.candidate_logit) == found


@pytest.mark.parametrize("name", RULES)
def test_each_rule_reads_what_it_declares(stage2, name):
    """Precomputed segment costs give the same keyframes where the rule reads them and are refused
    elsewhere; a rule that reads boundary scores refuses a model without offset evidence."""
    module, clips, lengths, read, bce = stage2
    rule = RULES[name]
    if rule.reads_segment_costs:
        assert rule(module.model, clips, lengths, PRICES, costs=bce) == rule(module.model, clips, lengths, PRICES)
    else:
        with pytest.raises(ValueError, match="reads no segment costs"):
            rule(module.model, clips, lengths, PRICES, costs=bce)
    plain = keyframe_module().eval()
    assert rule.runs_on(False) == (not rule.needs_boundary_scores)
    if rule.needs_boundary_scores:
        with pytest.raises(ValueError, match="boundary scores of offset_evidence"):
            rule(plain.model, clips, lengths, PRICES)
        with pytest.raises(ValueError, match="needs offset_evidence"):
            model_rule(name, offset_evidence=False)
    else:
        assert len(rule(plain.model, clips, lengths, PRICES)) == len(clips)
    kept = rule.kept_segments(read, PRICES)
    assert (kept is not None) == rule.prunes_segments


def test_an_unknown_rule_is_refused_naming_the_choices():
    with pytest.raises(ValueError, match=r"discovery must be one of \('offsets', 'boundaries', 'map', 'map_pruned', 'segmentation'\), got 'viterbi'"):
        rule_named("viterbi")


def test_rule_auto_tries_the_rules_cheapest_first():
    f1 = {name: 0.5 for name in RULES}
    assert fastest_rule(f1) == min(RULES.values(), key=lambda rule: rule.cost_rank).name
    assert len({rule.cost_rank for rule in RULES.values()}) == len(RULES)  # no ties to break by accident


def test_the_registry_imports_without_torch():
    code = "import sys, keyin.decode.registry; print('torch' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"


def test_no_module_but_the_registry_spells_a_rules_name():
    """Rules are asked what they read, never tested by name: a string constant equal to a registered
    rule's name appears in the registry module alone (conf/ and docs/ may name rules)."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        where = path.relative_to(PACKAGE).as_posix()
        if where == "decode/registry.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and node.value in RULES and (where, node.value) not in HOMONYMS:
                found.append(f"{where}:{node.lineno}: {node.value!r}")
    assert found == []
