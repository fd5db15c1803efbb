"""keyin-report's aggregation on a fabricated sweep folder."""

import json

import pytest
from omegaconf import OmegaConf

from keyin.cli import report
from keyin.eval.report import (
    collect_metrics, csv_table, markdown_table, method_sort_key, named_as_run, ranking_changes, row_source, summarise,
)


def write_job(root, name, method, seed, f1, version="0.2.0", **extra):
    job = root / name
    job.mkdir(parents=True)
    scores = dict(f1=f1, f1_tol1=f1 + 0.1, precision=f1, recall=f1, n_predicted=5.0)
    written_by = {} if version is None else {"keyin_version": version}  # keyin 0.1 wrote no version
    if version is not None:  # and no information-rule columns (docs/evaluation.md)
        scores.update(f1_interior=f1 - 0.05, f1_with_ends=f1 + 0.05, f1_tol1_interior=f1 + 0.05)
    (job / "metrics.json").write_text(
        json.dumps(dict(scores, method=method, dataset="brownian", seed=seed, **written_by, **extra))
    )


@pytest.fixture
def sweep(tmp_path):
    for seed, f1 in enumerate([0.5, 0.6, 0.7]):
        write_job(tmp_path, f"keyin_plus_seed{seed}", "keyin_plus", seed, f1)
    write_job(tmp_path, "surprise_seed0", "surprise", 0, 0.4,
              variants={"surprise_shift0": dict(f1=0.1, f1_tol1=0.3, precision=0.1, recall=0.1, n_predicted=6.0)})
    write_job(tmp_path, "random_seed0", "random", 0, 0.16)
    (tmp_path / "stage1_seed0").mkdir()  # a shared stage-1 dir holds no metrics
    tap = tmp_path / "tap_seed0"  # a subgoal predictor beside the sweep has no keyframe F1
    tap.mkdir()
    (tap / "metrics.json").write_text(json.dumps(dict(method="tap", dataset="pushing", seed=0, argmin_last=0.4)))
    frames = tmp_path / "frame_autoencoder_seed0"  # nor does a frame model
    frames.mkdir()
    (frames / "metrics.json").write_text(json.dumps(dict(method="frame_autoencoder", dataset="pushing", seed=0, bce_per_frame=9.0)))
    return tmp_path


def test_rows_average_over_seeds_in_the_papers_order_with_its_numbers(sweep):
    rows = summarise(collect_metrics(sweep))
    assert [row.method for row in rows] == ["random", "surprise", "surprise_shift0", "keyin_plus"]
    keyin = rows[-1]
    assert keyin.seeds == [0, 1, 2]
    assert keyin.mean["f1"] == pytest.approx(0.6) and keyin.std["f1"] == pytest.approx(0.1)  # n - 1
    assert keyin.paper_f1 == 0.84 and rows[2].paper_f1 is None
    assert rows[2].mean["f1"] == pytest.approx(0.1) and rows[0].std["f1"] == 0.0


def test_markdown_and_csv_carry_every_row(sweep):
    rows = summarise(collect_metrics(sweep))
    markdown = markdown_table(rows)
    assert "| brownian | keyin_plus | ours | 0.550 ± 0.100 | 0.650 ± 0.100 | 0.600 ± 0.100 | 0.84 | 0.650 | 0.700 |" in markdown
    assert "| brownian | surprise_shift0 | ours | – | – | 0.100 ± 0.000 | – | – |" in markdown  # a variant: no columns here
    lines = csv_table(rows).splitlines()
    assert len(lines) == 1 + len(rows)
    assert lines[0].startswith("dataset,method,seeds,paper_f1,f1_interior_mean,f1_interior_std,f1_with_ends_mean")
    assert lines[-1].startswith("brownian,keyin_plus,0 1 2,0.84,0.55,0.1,0.65,0.1,0.6,0.1")


def test_a_keyin_0_1_job_says_keyin_for_keyin_plus_and_is_reported_under_that_name(tmp_path):
    variants = {"keyin_offsets": dict(f1=0.2, f1_tol1=0.3, precision=0.2, recall=0.2, n_predicted=6.0)}
    write_job(tmp_path, "old/keyin_seed0", "keyin", 0, 0.5, version=None, variants=variants)
    write_job(tmp_path, "new/keyin_paper_seed0", "keyin_paper", 0, 0.1)
    rows = summarise(collect_metrics(tmp_path))
    assert [row.method for row in rows] == ["keyin_paper", "keyin_plus", "keyin_plus_offsets"]
    assert rows[1].mean["f1"] == pytest.approx(0.5) and rows[2].mean["f1"] == pytest.approx(0.2)
    assert "| brownian | keyin_plus | ours | – | – | 0.500 ± 0.000 | 0.84 | – |" in markdown_table(rows)


def test_a_seed_reported_twice_and_an_empty_folder_are_refused(sweep, tmp_path_factory):
    write_job(sweep, "again/keyin_plus_seed0", "keyin_plus", 0, 0.9)
    with pytest.raises(ValueError, match="appears twice"):
        summarise(collect_metrics(sweep))
    with pytest.raises(ValueError, match="no metrics.json"):
        collect_metrics(tmp_path_factory.mktemp("empty"))


def test_a_foreign_metrics_file_is_named(tmp_path):
    (tmp_path / "metrics.json").write_text(json.dumps({"accuracy": 1.0}))
    with pytest.raises(ValueError, match="lacks method, dataset, f1"):
        collect_metrics(tmp_path)


def test_several_sweep_folders_are_merged_by_method_and_seed(tmp_path):
    """Seed 0 in one sweep, seeds 1-2 in another (a table rebuilt after a lost run folder)."""
    write_job(tmp_path / "first", "keyin_plus_seed0", "keyin_plus", 0, 0.5)
    write_job(tmp_path / "first", "random_seed0", "random", 0, 0.2)
    for seed, f1 in [(1, 0.6), (2, 0.7)]:
        write_job(tmp_path / "second", f"keyin_plus_seed{seed}", "keyin_plus", seed, f1)
    rows = summarise(collect_metrics([tmp_path / "first", tmp_path / "second"]))
    assert [(row.method, row.seeds) for row in rows] == [("random", [0]), ("keyin_plus", [0, 1, 2])]
    assert rows[1].mean["f1"] == pytest.approx(0.6)
    nested = summarise(collect_metrics([tmp_path, tmp_path / "second"]))  # a folder inside another: read once
    assert [row.seeds for row in nested] == [[0], [0, 1, 2]]
    write_job(tmp_path / "third", "keyin_plus_seed2", "keyin_plus", 2, 0.9)
    with pytest.raises(ValueError, match="appears twice"):
        summarise(collect_metrics([tmp_path / "second", tmp_path / "third"]))


def test_keyin_report_takes_several_sweep_folders(tmp_path):
    write_job(tmp_path / "first", "keyin_plus_seed0", "keyin_plus", 0, 0.5)
    write_job(tmp_path / "second", "keyin_plus_seed1", "keyin_plus", 1, 0.7)
    report.main([str(tmp_path / "first"), str(tmp_path / "second"), "--out", str(tmp_path / "merged")])
    table = (tmp_path / "merged" / "table1.md").read_text()
    assert f"From `{tmp_path / 'first'}`, `{tmp_path / 'second'}`" in table
    assert "| brownian | keyin_plus | ours | 0.550 ± 0.141 | 0.650 ± 0.141 | 0.600 ± 0.141 | 0.84 |" in table


def test_the_papers_methods_come_first_and_our_additions_are_marked():
    methods = ["keyin_plus", "changepoint", "keyin_paper", "random", "surprise_shift0", "surprise", "keyin_plus_offsets"]
    ordered = sorted(methods, key=method_sort_key)
    assert ordered == ["random", "surprise", "keyin_paper", "surprise_shift0", "keyin_plus", "keyin_plus_offsets", "changepoint"]
    assert [row_source(m) for m in ordered] == ["paper"] * 3 + ["ours"] * 4


def test_a_row_of_the_papers_keyin_names_the_frame_model_and_sizes_it_changed(tmp_path):
    # Only a row named plain keyin_paper (or keyin_paper_stated_*) says it ran the paper's stated choices (issue 62).
    cpu_ours = dict(backbone="ours", scale="cpu")
    write_job(tmp_path, "keyin_paper_seed0", "keyin_paper", 0, 0.2, **cpu_ours)
    write_job(tmp_path, "delta_st_seed0", "keyin_paper_delta_st", 0, 0.3, **cpu_ours)
    write_job(tmp_path, "stated_seed0", "keyin_paper_stated_10k_5k", 0, 0.4, backbone="paper", scale="paper")
    write_job(tmp_path, "paper_cpu_seed0", "keyin_paper", 1, 0.5, backbone="paper", scale="cpu")
    write_job(tmp_path, "keyin_plus_seed0", "keyin_plus", 0, 0.9, **cpu_ours)
    rows = {row.method: row for row in summarise(collect_metrics(tmp_path))}
    assert sorted(rows) == [
        "keyin_paper · backbone=ours scale=cpu", "keyin_paper · scale=cpu", "keyin_paper_delta_st · backbone=ours scale=cpu",
        "keyin_paper_stated_10k_5k", "keyin_plus",
    ]
    assert {method: row_source(method) for method in rows} == {
        "keyin_paper · backbone=ours scale=cpu": "changed", "keyin_paper · scale=cpu": "changed",
        "keyin_paper_delta_st · backbone=ours scale=cpu": "changed", "keyin_paper_stated_10k_5k": "paper", "keyin_plus": "ours",
    }
    assert {row.paper_f1 for row in rows.values()} == {0.84}  # the paper's KEYIN figure beside each
    assert "| brownian | keyin_paper · backbone=ours scale=cpu | changed | 0.150 ± 0.000 |" in markdown_table(list(rows.values()))


def test_a_row_on_the_stated_frame_model_names_any_other_stated_value_its_job_config_changed(tmp_path):
    stated = dict(backbone="paper", scale="paper")
    as_stated = {"model": {"keyframes": {"lr": 2e-4, "frozen": "lstm_inter", "delta_input": "argmax"}},
                 "scale": {"batch_size": 30}}
    changed = {"model": {"keyframes": {"lr": 1e-3, "frozen": "lstm_inter", "delta_input": "soft"}},
               "scale": {"batch_size": 30}}
    for name, config, where in (("stated", as_stated, "config.yaml"), ("changed", changed, ".hydra/config.yaml"),
                                ("unknown", None, None)):  # committed job folder, run dir, no config
        write_job(tmp_path, f"{name}_seed0", "keyin_paper", {"stated": 0, "changed": 1, "unknown": 2}[name], 0.3, **stated)
        if config is not None:
            (tmp_path / f"{name}_seed0" / where).parent.mkdir(exist_ok=True)
            (tmp_path / f"{name}_seed0" / where).write_text(OmegaConf.to_yaml(OmegaConf.create(config)))
    names = sorted({record["method"] for record in collect_metrics(tmp_path)})
    assert names == ["keyin_paper", "keyin_paper · model.keyframes.lr=0.001 model.keyframes.delta_input=soft"]
    assert row_source(names[1]) == "changed"
    lost = {"model": {"keyframes": {"lr": "${oops.lr}"}}}  # a key its config cannot resolve is not known changed
    assert named_as_run("keyin_paper", stated, OmegaConf.create(lost)) == "keyin_paper"


def test_a_renamed_row_draws_the_predictions_its_job_saved_under_its_own_name(tmp_path):
    write_job(tmp_path, "keyin_paper_seed0", "keyin_paper", 0, 0.2, backbone="ours", scale="cpu")
    saved = {"predicted": {"keyin_paper": [[3, 7]]}, "truth": [[3, 8]]}
    (tmp_path / "keyin_paper_seed0" / "predictions.json").write_text(json.dumps(saved))
    job, predicted, truth = report.example_predictions(collect_metrics(tmp_path), "brownian")
    assert job == tmp_path / "keyin_paper_seed0" and truth == [[3, 8]]
    assert predicted == {"keyin_paper · backbone=ours scale=cpu": [[3, 7]]}


def test_each_row_says_its_jobs_mean_wall_time_and_a_variant_none(tmp_path):
    for seed, minutes in enumerate([10, 20]):
        write_job(tmp_path, f"surprise_seed{seed}", "surprise", seed, 0.4, train_seconds=60 * minutes, score_seconds=90,
                  variants={"surprise_shift0": dict(f1=0.1, f1_tol1=0.3, precision=0.1, recall=0.1, n_predicted=6.0)})
    rows = markdown_table(summarise(collect_metrics(tmp_path))).splitlines()
    assert rows[2].endswith("| 15.0 + 1.5 | 2 |") and rows[3].endswith("| – | 2 |")


def test_wall_times_average_the_seeds_that_recorded_them_and_name_those(tmp_path):
    write_job(tmp_path, "keyin_paper_seed0", "keyin_paper", 0, 0.2)  # written before jobs timed themselves
    for seed, minutes in [(1, 10), (2, 30)]:
        write_job(tmp_path, f"keyin_paper_seed{seed}", "keyin_paper", seed, 0.2, train_seconds=60 * minutes, score_seconds=30)
    write_job(tmp_path, "static_seed0", "static", 0, 0.3)
    rows = markdown_table(summarise(collect_metrics(tmp_path))).splitlines()
    assert rows[2].startswith("| brownian | static |") and rows[2].endswith("| – | 1 |")
    assert rows[3].startswith("| brownian | keyin_paper |") and rows[3].endswith("| 20.0 + 0.5 (seeds 1, 2) | 3 |")


def test_brief_prints_each_methods_f1_beside_the_papers_and_writes_nothing(sweep, capsys):
    report.main([str(sweep), "--brief"])
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "| dataset | method | F1 interior | F1 (paper) | metrics |"
    keyin_plus = next(line for line in lines if "| keyin_plus |" in line)
    assert "| 0.550 ± 0.100 | 0.84 |" in keyin_plus  # interior F1 0.45, 0.55, 0.65 over seeds 0-2
    assert all(f"{sweep}/keyin_plus_seed{seed}/metrics.json" in keyin_plus for seed in range(3))
    assert not (sweep / "report").exists()


def test_the_ranking_paragraph_names_each_method_whose_rank_moves_with_the_tolerance(tmp_path):
    # exact: a 0.9 > b 0.5 > c 0.3; at ±1: c 0.95 > a 0.92 > b 0.6; at ±2 only b and c were scored: c > b
    for name, exact, tol1, tol2 in (("a", 0.9, 0.92, None), ("b", 0.5, 0.6, 0.7), ("c", 0.3, 0.95, 0.99)):
        tol2_scores = {} if tol2 is None else dict(f1_tol2=tol2, f1_tol2_interior=tol2)
        write_job(tmp_path, f"{name}_seed0", name, 0, exact, f1_tol1_interior=tol1, **tol2_scores)
    said = ranking_changes(summarise(collect_metrics(tmp_path)))
    assert "- brownian, ranks by exact F1 → at ±1: a 1 → 2, b 2 → 3, c 3 → 1." in said
    assert "- brownian, ranks by exact F1 → at ±2: b 1 → 2, c 2 → 1 (not scored at ±2: a; their jobs predate the column)." in said
    assert "±2 F1 interior" in markdown_table(summarise(collect_metrics(tmp_path)))
