"""Schemas and cross-field rules of the config sections batista2011, tereshkov, measured and
discrepancy (workflow/schemas/<stage>.schema.yaml and the stage rules in check_config,
common.smk).

Each broken config is the CI config with one change, given as the whole config
(--replace-workflow-config, so that a deleted key stays deleted): it must fail while the
Snakefile is parsed, before the DAG is built, with one line naming the config file, the key
and what is wrong (every case parsed in-process; one per stage through `snakemake -n`).
Valid configs at the edges of every rule pass, so the checks do not reject good values.
"""

import copy

import jsonschema
import pytest
import yaml

from tests.configs import ci_config, load_config
from snakemake.exceptions import MissingInputException
from snakemake.common.configfile import load_configfile

from tests.conftest import config_error, write_config
from tests.snakemake_plan import planned_jobs
from tests.test_workflow import CI, REPO, snakemake

DEFAULT = REPO / "config" / "config.yaml"
SCHEMAS = REPO / "workflow" / "schemas"
STAGES = ("batista2011", "tereshkov", "measured", "gyro", "noise")


def schema(stage):
    return yaml.safe_load((SCHEMAS / f"{stage}.schema.yaml").read_text())


def _parent(cfg, dotted):
    *path, last = dotted.split(".")
    for k in path:
        cfg = cfg[k]
    return cfg, last


#: Value of a change that removes the key.
DELETE = object()


def changed(changes):
    """The CI config with ``{"a.b.c": value}`` changes (value ``DELETE`` removes the key)."""
    cfg = ci_config()
    for dotted, value in changes.items():
        parent, last = _parent(cfg, dotted)
        if value is DELETE:
            del parent[last]
        else:
            parent[last] = copy.deepcopy(value)
    return cfg


def dry_run(tmp_path, cfg):
    path = write_config(cfg, tmp_path / "config.yaml")
    workdir = tmp_path / "work"
    workdir.mkdir()
    proc = snakemake(workdir, "-n", "all", "--configfile", path, "--replace-workflow-config", timeout=180)
    return path, workdir, proc


BROKEN = {
    # ---------------------------------------------------------------- batista2011
    "batista_wrong_type": (changed({"batista2011.calibration.runs": "500"}),
                           "batista2011.calibration.runs: '500' is not of type 'integer'"),
    "batista_negative_runs": (changed({"batista2011.filter.runs": -5}),
                              "batista2011.filter.runs: -5 is less than the minimum of 2"),
    "batista_missing_key": (changed({"batista2011.filter.theta": DELETE}),
                            "batista2011.filter: 'theta' is a required property"),
    "batista_unknown_key": (changed({"batista2011.calibration.schedule.rate_hz": 100.0}),
                            "batista2011.calibration.schedule: Additional properties are not allowed "
                            "('rate_hz' was unexpected)"),
    "batista_short_vector": (changed({"batista2011.filter.xi": [1e-3, 1e-4]}),
                             "batista2011.filter.xi: [0.001, 0.0001] is too short"),
    "batista_zero_axis": (changed({"batista2011.observability.axis_body": [0, 0, 0]}),
                          "batista2011.observability.axis_body: [0, 0, 0] should not be valid"),
    "batista_window_in_transition": (changed({"batista2011.calibration.schedule.window_start_s": 1.0}),
                                     "batista2011.calibration.schedule.window_start_s: the data window 1.0-5.0 s "
                                     "must lie in the static part 2.0-22.0 s of each step"),
    "batista_window_past_step": (changed({"batista2011.calibration.schedule.window_start_s": 19.0}),
                                 "batista2011.calibration.schedule.window_start_s: the data window 19.0-23.0 s"),
    "batista_steady_after_run": (changed({"batista2011.filter.steady_from_s": 150.0}),
                                 "batista2011.filter.steady_from_s: 150.0 s leaves no steady state"),
    "batista_gramian_longer_than_run": (changed({"batista2011.observability.gramian_window_s": 200.0}),
                                        "batista2011.observability.gramian_window_s: 200.0 s exceeds the run"),
    # ------------------------------------------------------------------ tereshkov
    "tereshkov_bad_enum": (changed({"tereshkov.estimator.accel_formula": "eq15"}),
                           "tereshkov.estimator.accel_formula: 'eq15' is not one of ['eq14', 'eq13']"),
    "tereshkov_negative_runs": (changed({"tereshkov.scenarios.field.runs": -1}),
                                "tereshkov.scenarios.field.runs: -1 is less than the minimum of 1"),
    "tereshkov_wrong_type": (changed({"tereshkov.estimator.accel_feedback": "yes"}),
                             "tereshkov.estimator.accel_feedback: 'yes' is not of type 'boolean'"),
    "tereshkov_missing_key": (changed({"tereshkov.monte_carlo.steady_state_from_s": DELETE}),
                              "tereshkov.monte_carlo: 'steady_state_from_s' is a required property"),
    "tereshkov_unknown_key": (changed({"tereshkov.vehicle.turn_radius_m": 10.0}),
                              "tereshkov.vehicle: Additional properties are not allowed ('turn_radius_m' was "
                              "unexpected)"),
    "tereshkov_inverted_range": (changed({"tereshkov.vehicle.cruise_mps": [4.0, 2.5]}),
                                 "tereshkov.vehicle.cruise_mps: low end 4.0 exceeds high end 2.5"),
    "tereshkov_inverted_claim_range": (changed({"tereshkov.claims.convergence_ratio_range": [2.0, 0.5]}),
                                       "tereshkov.claims.convergence_ratio_range: low end 2.0 exceeds high end 0.5"),
    "tereshkov_zero_turn_angle": (changed({"tereshkov.vehicle.turn_deg": [0, 360]}),
                                  "tereshkov.vehicle.turn_deg.0: 0 is less than or equal to the minimum of 0"),
    "tereshkov_steady_after_run": (changed({"tereshkov.sweep.steady_state_from_s": 700}),
                                   "tereshkov.sweep.steady_state_from_s: 700 s leaves no steady state"),
    "tereshkov_turn_below_straight": (changed({"tereshkov.estimator.turn_rate_dps": 0.5}),
                                      "tereshkov.estimator.turn_rate_dps: 0.5 must exceed straight_rate_dps = 1.0"),
    "tereshkov_gnss_faster_than_imu": (changed({"tereshkov.gnss.rate_hz": 15}),
                                       "tereshkov.gnss.rate_hz: 15 Hz exceeds the IMU rate comparison.imu_rate_hz"),
    # ------------------------------------------------------------------- measured
    "measured_unknown_recording": (changed({"measured.recordings.adis16475": {"g": 9.81,
                                                                             "estimators": ["full_lls"]}}),
                                   "measured.recordings: 'adis16475' is not one of ['xsens_mti', 'mpu6050', "
                                   "'imucal_ferraris', 'imutk_fork_data2'"),
    "measured_bad_estimator": (changed({"measured.recordings.xsens_mti.estimators": ["full_lls", "magic"]}),
                               "measured.recordings.xsens_mti.estimators.1: 'magic' is not a registered estimator; "
                               "known: full_lls, full_als, full_nlls, bias_lls, bias_nlls"),
    # ------------------------------------------- names checked against the registry (no enums)
    "burkhard_bad_method": (changed({"burkhard2024.experiments.fig1b.methods": ["full_lls", "full_lsq"]}),
                            "burkhard2024.experiments.fig1b.methods.1: 'full_lsq' is not a registered estimator"),
    "measured_missing_key": (changed({"measured.bootstrap.level": DELETE}),
                             "measured.bootstrap: 'level' is a required property"),
    "measured_unknown_key": (changed({"measured.recordings.mpu6050.pose_selection": "all"}),
                             "measured.recordings.mpu6050: Additional properties are not allowed ('pose_selection' "
                             "was unexpected)"),
    "measured_negative_replicates": (changed({"measured.bootstrap.replicates": -10}),
                                     "measured.bootstrap.replicates: -10 is less than the minimum of 1"),
    "measured_wrong_type": (changed({"measured.static.window": "1s"}),
                            "measured.static.window: '1s' is not of type 'number'"),
    "measured_g_in_g_units": (changed({"measured.recordings.mpu6050.g": 1.0}),
                              "measured.recordings.mpu6050.g: 1.0 is less than the minimum of 9.7"),
    # ---------------------------------------------------------------- discrepancy
    "discrepancy_confusion_size_not_scored": (changed({"discrepancy.benchmark.confusion_size_mde": 2.0}),
                                              "discrepancy.benchmark.confusion_size_mde: 2.0 is not in sizes_mde "
                                              "[3.0]"),
    "discrepancy_recording_not_measured": (changed({"discrepancy.recordings": ["xsens_mti", "adis_unknown"]}),
                                           "discrepancy.recordings: adis_unknown not in measured.recordings"),
    "discrepancy_same_imu_not_analysed": (changed({"discrepancy.sessions.same_imu":
                                                   {"one": ["mpu6050", "imucal_ferraris"]}}),
                                          "discrepancy.sessions.same_imu.one: imucal_ferraris not in "
                                          "discrepancy.recordings"),
    # ----------------------------------------------------------------------- gyro
    "gyro_unknown_session": (changed({"gyro.sessions": ["xsens", "ctu"]}),
                             "gyro.sessions.1: 'ctu' is not a gyro session; known: xsens, fork_data1"),
    "gyro_too_few_motions": (changed({"gyro.ipopt_check.motions": 4}),
                             "gyro.ipopt_check.motions: 4 is less than the minimum of 5"),
    "gyro_unknown_key": (changed({"gyro.monte_carlo.chunks": 2}),
                         "gyro.monte_carlo: Additional properties are not allowed ('chunks' was unexpected)"),
    # --------------------------------------------------------------------- noise
    "noise_duplicate_configuration": (changed({"noise.coverage.configurations": [
        {"name": "white", "white": 2e-3, "quantization": 0.0, "bias_instability": 0.0, "random_walk": 0.0,
         "drift_ramp": 0.0}] * 2}), "noise.coverage.configurations: configuration names must be distinct"),
    "noise_factor_below_one": (changed({"noise.claims.datasheet_factor": 0.5}),
                               "noise.claims.datasheet_factor: 0.5 is less than or equal to the minimum of 1"),
    "noise_term_missing": (changed({"noise.coverage.configurations": [
        {"name": "white", "white": 2e-3, "quantization": 0.0, "bias_instability": 0.0, "random_walk": 0.0}]}),
        "noise.coverage.configurations.0: 'drift_ramp' is a required property"),
    "noise_too_few_bootstrap_draws": (changed({"noise.adis.n_boot": 10}),
                                      "noise.adis.n_boot: 10 is less than the minimum of 50"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_stage_config_is_rejected_with_its_key_and_what_is_wrong(tmp_path, case):
    """Every broken config is rejected while the Snakefile is parsed (in this process: the
    same check_config as the command line), with one line naming the file, the key and
    what is wrong."""
    cfg, message = BROKEN[case]
    path = tmp_path / "config.yaml"
    error = config_error(cfg, path)
    assert error is not None, "the broken config was accepted"
    assert "\n" not in error and error.startswith("invalid config"), error
    assert str(path) in error and message in error, error


#: One broken config per stage through the command line (the rest differ only in the message).
CLI_CASES = ("batista_window_in_transition", "tereshkov_inverted_range", "measured_bad_estimator",
             "discrepancy_confusion_size_not_scored", "noise_duplicate_configuration")


@pytest.mark.parametrize("case", CLI_CASES)
def test_broken_stage_config_fails_the_dry_run_before_any_job(tmp_path, case):
    cfg, message = BROKEN[case]
    path, workdir, proc = dry_run(tmp_path, cfg)
    out = proc.stdout + proc.stderr  # Snakemake logs to stderr, to stdout in a dry run
    assert proc.returncode != 0, out[-2000:]
    lines = [ln for ln in out.splitlines() if ln.startswith("invalid config")]
    assert len(lines) == 1, out
    assert str(path) in lines[0] and message in lines[0], lines[0]
    assert "Traceback" not in out
    assert "Job stats" not in out, "the DAG was built despite the broken config"
    assert not (workdir / "results").exists()


def test_a_missing_imutk_run_is_the_gyro_jobs_missing_input_not_a_parse_check(tmp_path):
    """IMU-TK's run from source is an input of the gyro sessions job: a config naming a file
    that does not exist plans no job and names the file (Snakemake's own missing-input
    error), while the workflow's parse reads no file system."""
    cfg = changed({"gyro.imutk_run": "results/gyro/peers/none.json"})
    path = tmp_path / "config.yaml"
    assert config_error(cfg, path) is None  # the parse accepts it
    workdir = tmp_path / "work"
    workdir.mkdir()
    with pytest.raises(MissingInputException, match=r"results/gyro/peers/none\.json"):
        planned_jobs(workdir, ["all"], [path], replace_config=True)  # `snakemake -n all`, in this process
    assert not (workdir / "results").exists()


# Valid configs at the edges of the rules above (the same checks must let them through):
# the changes of each stage to the CI config.
EDGE_CHANGES = {
    "batista2011": {"batista2011.calibration.runs": 2, "batista2011.filter.runs": 2,
                    "batista2011.calibration.schedule.window_start_s": 2.0,  # = transition_s
                    "batista2011.calibration.schedule.window_s": 20.0,  # ends with the step
                    "batista2011.filter.steady_from_s": 0.0,
                    "batista2011.observability.gramian_window_s": 150.0},  # = filter.duration_s
    "tereshkov": {"tereshkov.vehicle.cruise_mps": [3.0, 3.0], "tereshkov.imu.gyro_bias_dps": [0.0, 0.0],
                  "tereshkov.vehicle.terrain_terms": 0, "tereshkov.vehicle.first_straight_s": 45.0,
                  "tereshkov.estimator.accel_formula": "eq13", "tereshkov.estimator.turn_rate_dps": 1.01,
                  "tereshkov.gnss.rate_hz": 10, "tereshkov.comparison.imu_rate_hz": 10,
                  "tereshkov.sweep.kinds": ["all"], "tereshkov.sweep.steady_state_from_s": 699},
    "measured": {"measured.recordings.imucal_ferraris": {
        "g": 9.81, "estimators": ["full_lls", "bias_lls"], "pose_selection": "all"}},
    "gyro": {"gyro.sessions": ["imucal_ferraris"], "gyro.monte_carlo.trials": 2,
             "gyro.ipopt_check.motions": 5, "gyro.integrators.angle_deg": 360},
    # one record (3 axes: the coverage rule can fail from 2), the least factor above 1, 50 draws
    "noise": {"noise.coverage.records": 1, "noise.claims.datasheet_factor": 1.001, "noise.adis.n_boot": 50,
              "noise.coverage.samples": 4096, "noise.claims.coverage_floor": 0.99},
}


@pytest.mark.parametrize("stage", STAGES)
def test_valid_configs_at_the_edges_pass_the_checks(tmp_path, stage):
    """Each stage's edges alone pass every check of the parse (check_config and the
    schemas, in this process as for the broken configs above)."""
    assert config_error(changed(EDGE_CHANGES[stage]), tmp_path / "config.yaml") is None


def test_valid_configs_at_the_edges_pass_the_dry_run(tmp_path):
    """Every stage's edges at once (they change disjoint keys) through `snakemake -n all`,
    planned in this process (tests/snakemake_plan.py): the checks accept them and the DAG is
    built, with every stage's jobs in it.  Which stage's edge a failure comes from, the
    message names (its key) and the per-stage parse test above tells apart."""
    changes = {k: v for stage in STAGES for k, v in EDGE_CHANGES[stage].items()}
    assert len(changes) == sum(map(len, EDGE_CHANGES.values()))  # disjoint: no stage's edge overwritten
    path = write_config(changed(changes), tmp_path / "config.yaml")
    workdir = tmp_path / "work"
    workdir.mkdir()
    rules = {rule for rule, _ in planned_jobs(workdir, ["all"], [path], replace_config=True).values()}
    assert {"all", "batista2011_claims", "tereshkov_claims", "measured_claims", "gyro_claims", "noise_claims"} <= rules
    assert not (workdir / "results").exists()


@pytest.mark.parametrize("config", [DEFAULT, CI], ids=["config.yaml", "ci.yaml"])
def test_both_configs_validate(config):
    cfg = load_config(config.name)
    for stage in STAGES:
        s = schema(stage)
        jsonschema.Draft202012Validator.check_schema(s)
        errors = [f"{stage}.{'.'.join(map(str, e.absolute_path))}: {e.message}"
                  for e in jsonschema.Draft202012Validator(s).iter_errors(cfg[stage])]
        assert not errors, errors


# The default config's dry run: tests/test_workflow.py::test_dry_run_on_the_default_config.


def test_every_key_is_required_and_no_other_key_allowed():
    """Every object of the stages' schemas lists all its properties as required and forbids
    others, except measured.recordings (a subset of the known recordings, by name)."""
    def walk(s, where):
        if "properties" in s and where != "measured.recordings":
            assert s.get("additionalProperties") is False, where
            assert sorted(s.get("required", [])) == sorted(s["properties"]), where
        for k, sub in s.get("properties", {}).items():
            walk(sub, f"{where}.{k}")

    for stage in STAGES:
        walk(schema(stage), stage)


def test_no_schema_restates_the_estimator_registry():
    """Estimator names are checked against the registry by check_config, never listed in a
    schema (a new estimator would otherwise need every schema edited)."""
    from accelcal.registry import ESTIMATORS

    for path in SCHEMAS.glob("*.schema.yaml"):
        enums = []

        def walk(node):
            if isinstance(node, dict):
                enums.extend(node.get("enum", []))
                for v in node.values():
                    walk(v)
            elif isinstance(node, list):
                for v in node:
                    walk(v)

        walk(yaml.safe_load(path.read_text()))
        assert not set(enums) & set(ESTIMATORS), (path.name, set(enums) & set(ESTIMATORS))


def test_named_choices_match_the_library():
    """The schemas' enums are the names the code accepts (a renamed estimator, recording or
    option would otherwise pass the schema and fail in a job, or the reverse)."""
    from accelcal.registry import ESTIMATORS
    from accelcal_repro.measured.sources import FERRARIS_STATIC, SOURCES
    from accelcal.tereshkov.errors import InvalidParameterError
    from accelcal.tereshkov.estimator import TereshkovParams

    rec = schema("measured")["properties"]["recordings"]
    assert set(rec["propertyNames"]["enum"]) == set(rec["properties"]) == set(SOURCES)
    # the cross-field rule's numbers: six static positions, ten poses for a full model
    assert len(FERRARIS_STATIC) == 6 and ESTIMATORS["full_lls"].min_poses == 10
    formulas = schema("tereshkov")["properties"]["estimator"]["properties"]["accel_formula"]["enum"]
    for f in formulas:
        TereshkovParams(accel_formula=f)
    with pytest.raises(InvalidParameterError):
        TereshkovParams(accel_formula="eq15")


# The two rules that need the reproductions' code are checked by their jobs (parsing the
# Snakefile imports no reproduction), with the same one-line message naming the key.
def test_first_call_names_are_checked_by_the_compile_job():
    from accelcal.errors import AccelcalError
    from accelcal_repro.first_calls import check_calls

    check_calls("all")
    check_calls(["bias_lls", "full_lls"])
    with pytest.raises(AccelcalError, match=r"^benchmark.compile_calls.1: 'full_nlls' is not a first call of a "
                                            r"compiled kernel; known: full_lls, bias_lls, full_als"):
        check_calls(["bias_lls", "full_nlls"])


def test_full_models_on_a_section_list_are_refused_by_the_measured_job():
    from accelcal.errors import TooFewPosesError
    from accelcal_repro.measured.calibrate import check_section_list_estimators

    sections = {"x_p": (0, 10)}
    check_section_list_estimators("imucal_ferraris", ["bias_lls", "bias_nlls"], sections, "section_list")
    check_section_list_estimators("imucal_ferraris", ["full_lls"], sections, "all")
    check_section_list_estimators("mpu6050", ["full_lls"], None, "section_list")
    with pytest.raises(TooFewPosesError, match=r"^measured.recordings.imucal_ferraris.estimators: full_lls need at "
                                               r"least 10 poses, pose_selection 'section_list' gives the session's 6"):
        check_section_list_estimators("imucal_ferraris", ["full_lls", "bias_lls"], sections, "section_list")


@pytest.mark.parametrize("case", ["batista_missing_key", "measured_unknown_recording", "noise_term_missing"])
def test_a_config_the_tests_write_reads_as_its_yaml_would(tmp_path, case):
    """The tests write configs as JSON (tests/conftest.write_config: Snakemake reads JSON
    first, and its YAML path is the slow part of a parse): Snakemake gets the same dict as
    from the YAML a user would write (broken configs included)."""
    cfg, _ = BROKEN[case]
    as_yaml = tmp_path / "config.yaml"
    as_yaml.write_text(yaml.safe_dump(cfg))
    assert load_configfile(write_config(cfg, tmp_path / "config.json")) == load_configfile(as_yaml) == cfg
