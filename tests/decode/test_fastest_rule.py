"""The recorded choice of keyin-discover's default rule: the cheapest rule within 0.01 of map's
validation F1 (keyin.decode.registry.fastest_rule), known answers."""

import pytest

from keyin.decode.registry import fastest_rule


@pytest.mark.parametrize("val_f1, chosen", [
    ({"map": 0.926, "offsets": 0.879, "boundaries": 0.871}, "map"),           # Brownian: the cheap rules 0.05 below
    ({"map": 0.255, "offsets": 0.284, "boundaries": 0.292}, "boundaries"),    # both cheap rules above map
    ({"map": 0.300, "offsets": 0.295, "boundaries": 0.250}, "offsets"),       # offsets within 0.01, boundaries not
    ({"map": 0.300, "offsets": 0.290}, "offsets"),                            # exactly 0.01 below counts
    ({"map": 0.300, "offsets": 0.2899}, "map"),
    ({"map": 0.300}, "map"),                                                  # a model without cheap rules scored
])
def test_the_cheapest_rule_within_the_tolerance_of_map(val_f1, chosen):
    assert fastest_rule(val_f1) == chosen


def test_without_maps_score_there_is_nothing_to_compare_with():
    with pytest.raises(ValueError, match="map's validation F1"):
        fastest_rule({"offsets": 0.5})
