"""A config per learner (issue 46, item 1): the run settings every learner shares, each learner's own
settings registered with it, composed into one config class per learner; a field a learner does not
have is one line, wherever it is set; the presets are data a learner takes the fields it has of."""

from __future__ import annotations

import dataclasses
import pickle

import pytest

from egosearch.rl.config import (
    LearnerConfig,
    config_class,
    field_defaults,
    field_order,
    load_config,
    own_settings,
    shared_fields,
)
from egosearch.rl.learner_registry import LEARNERS
from egosearch.rl.presets import CPU, PRESETS
from egosearch.rl.run_settings import RunSettings
from egosearch.variants import VariantError, load_variant

SHARED = set(shared_fields())
"""The fields every learner has: the run settings' and the observation options'."""

SHIPPED = list(LEARNERS)
"""The learners registered at import (a test's toy learner comes and goes inside its test)."""


def test_a_learners_own_fields_are_those_its_settings_class_declares_and_none_is_a_run_setting():
    # no hand-kept count: a field added to a settings class is one of its learner's fields, and only its
    for name in SHIPPED:
        declared = {f.name for f in dataclasses.fields(LEARNERS[name].settings_class())}
        assert set(own_settings(name)) == declared, name
    assert {f.name for f in dataclasses.fields(RunSettings)} < SHARED and "contact_signal" in SHARED
    # every field belongs to the shared settings or to some learner, and none to both
    assert SHARED | {f for name in LEARNERS for f in own_settings(name)} == set(field_defaults()) == set(field_order())
    assert not SHARED & {f for name in LEARNERS for f in own_settings(name)}


@pytest.mark.parametrize("algorithm", SHIPPED)
def test_a_learners_config_is_the_run_settings_and_its_own(algorithm):
    valid = {"ppo": {"init_steps": 0, "update_every": 8}}  # PPO's rules: no warm-up, a rollout of whole steps
    cfg = LearnerConfig(algorithm=algorithm, **valid.get(algorithm, {})).validate()
    assert type(cfg) is config_class(algorithm) and isinstance(cfg, LearnerConfig)
    assert set(cfg.to_dict()) == SHARED | set(own_settings(algorithm))
    assert LEARNERS[algorithm].settings_class() is not None
    assert pickle.loads(pickle.dumps(cfg)) == cfg  # a worker process may be handed one
    assert LearnerConfig.from_dict(cfg.to_dict()) == cfg


def test_the_default_config_is_the_papers_learner():
    assert type(LearnerConfig()).__name__ == "SacCurlConfig" and LearnerConfig().algorithm == "sac_curl"


def test_a_field_another_learner_has_is_one_line_naming_it_the_learner_and_its_fields():
    with pytest.raises(ValueError) as err:
        load_config("paper", {"algorithm": "sac_curl", "obs_downsample": 2})
    line = str(err.value)
    assert "\n" not in line
    assert "algorithm sac_curl (SAC+CURL) has no field 'obs_downsample'" in line
    assert "a setting of sac_drq, sac_drq_recurrent, ppo" in line and "crop_size" in line  # its own fields
    with pytest.raises(ValueError, match="algorithm ppo .* has no field 'alpha_lr'"):
        load_config("cpu", {"algorithm": "ppo", "alpha_lr": 1e-3})
    with pytest.raises(ValueError, match="algorithm sac_drq_recurrent .* has no field 'critic_layer_norm'"):
        LearnerConfig.from_dict({"algorithm": "sac_drq_recurrent", "critic_layer_norm": True})


def test_a_field_no_learner_has_names_the_nearest():
    with pytest.raises(ValueError, match=r"unknown LearnerConfig field 'obs_downsampel' \(did you mean "
                                         r"obs_downsample\?\) for algorithm sac_drq"):
        load_config("cpu", {"obs_downsampel": 2})


def test_a_preset_sets_the_fields_a_learner_has_and_leaves_the_others():
    # PPO's own rules only: the cpu preset's demonstration fields never reach a learner that does not read them
    cfg = load_config("cpu", {"algorithm": "ppo", "init_steps": 0, "n_step": 1, "update_every": 16,
                              "replay_capacity": 1000})
    assert cfg.obs_downsample == CPU["obs_downsample"] and not hasattr(cfg, "aug_pad")
    assert not hasattr(cfg, "demo_episodes") and not hasattr(cfg, "critic_warmup_updates")  # no such aid
    assert cfg.critic_privileged_state == CPU["critic_privileged_state"]  # PPO's value network reads it
    with pytest.raises(ValueError, match=r"ppo .* no field 'demo_episodes' \(a setting of sac_drq, sac_drq_rec"):
        load_config("cpu", {"algorithm": "ppo", "init_steps": 0, "update_every": 16, "demo_episodes": 10})
    assert not hasattr(cfg, "alpha_lr")  # the cpu preset's temperature rate: PPO has no temperature
    for preset in PRESETS:
        assert set(load_config(preset).to_dict()) <= set(field_defaults())


def test_a_variant_naming_its_learner_is_checked_against_it_when_read(tmp_path):
    (tmp_path / "curl_pooled.yaml").write_text(
        "name: curl_pooled\nenv_id: EgoSearch-v0\ntrain_env: {layout: kitchen_living, placement: everywhere}\n"
        "config:\n  algorithm: sac_curl\n  aug_pad: 2\n")
    with pytest.raises(VariantError, match="curl_pooled.yaml: config: algorithm sac_curl .* has no field 'aug_pad'"):
        load_variant("curl_pooled", tmp_path)


def test_a_learner_registered_without_settings_has_the_run_settings_alone():
    from egosearch.rl.learner_registry import register

    register("toy_settingless", "toy", "somewhere:Agent")
    try:
        cfg = load_config("smoke", {"algorithm": "toy_settingless"})
        assert set(cfg.to_dict()) == SHARED
        # at the cpu preset too, with nothing pinned: the preset's demonstrations and privileged critic are
        # for the learners that read them
        assert not hasattr(load_config("cpu", {"algorithm": "toy_settingless"}), "critic_privileged_state")
        with pytest.raises(ValueError, match="has no field 'actor_lr'"):
            load_config("smoke", {"algorithm": "toy_settingless", "actor_lr": 1e-3})
    finally:
        del LEARNERS["toy_settingless"]


def test_config_show_gives_every_field_once_with_its_value_source_and_declaring_file(capsys):
    """What a reader opens one learner's config with: each field once, its value and where it comes from (the
    field's default, the preset, the variant), the class and file that declare it."""
    import importlib
    import inspect

    from egosearch.cli import main
    from egosearch.rl.config import config_sources

    rows = {r["field"]: r for r in config_sources("sac_drq", "cpu")}
    assert set(rows) == set(LearnerConfig(algorithm="sac_drq").to_dict())
    assert (rows["total_env_steps"]["value"], rows["total_env_steps"]["source"], rows["total_env_steps"]["paper"]) == (
        "200000", "preset cpu", "750000")
    assert (rows["gamma"]["value"], rows["gamma"]["source"]) == ("0.99", "default")
    assert rows["algorithm"]["declared_in"] == "egosearch.rl.run_settings.RunSettings"
    for row in rows.values():  # the named class's own source declares the field
        module, klass = row["declared_in"].rsplit(".", 1)
        assert f"    {row['field']}:" in inspect.getsource(getattr(importlib.import_module(module), klass)), row
    ppo = {r["field"]: r for r in config_sources("ppo", "cpu", {"init_steps": 0, "update_every": 16, "n_step": 1})}
    # PPO opts into one training aid, not the other
    assert "demo_episodes" not in ppo and ppo["critic_privileged_state"]["source"] == "preset cpu"
    paper = {r["field"]: r for r in config_sources("sac_drq", "paper")}
    assert (paper["total_env_steps"]["value"], paper["total_env_steps"]["source"]) == ("750000", "default")
    varied = {r["field"]: r
              for r in config_sources("sac_drq", "cpu", {"contact_signal": True}, "head_on_contact_signal")}
    assert (varied["contact_signal"]["value"], varied["contact_signal"]["source"]) == (
        "True", "variant head_on_contact_signal")

    main(["config", "show", "sac_drq", "--variant", "head_on_contact_signal"])
    out = capsys.readouterr().out.splitlines()
    n = len(dataclasses.fields(config_class("sac_drq")))
    assert out[0].startswith(f"sac_drq at preset cpu with variant head_on_contact_signal: {n} fields, declared in ")
    # the header, the variant's env_id and train_env, the column heads, then one line a field
    assert len(out) == 4 + n and sum(line.startswith("contact_signal ") for line in out) == 1
    assert main(["config", "show", "sac_curl", "--variant", "head_on_ppo"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("--variant head_on_ppo trains algorithm ppo, not sac_curl: show that one")


def test_a_training_aid_is_a_piece_its_learners_opt_into_and_is_listed_where_it_always_was():
    """The demonstrations and the privileged critic (rl/training_aids.py) are fields only of the learners whose
    settings name them; a variant that turns them off means, for a learner without them, what it already is;
    one that turns them on is refused there; and their fields are listed after the run setting each names."""
    from egosearch.rl.training_aids import (
        TRAINING_AIDS,
        DemonstrationSettings,
        PrivilegedCriticSettings,
        critic_reads_state,
        demonstration_settings,
    )

    shipped = {"sac_curl": set(), "sac_drq": set(TRAINING_AIDS), "sac_drq_recurrent": set(TRAINING_AIDS),
               "ppo": {PrivilegedCriticSettings}}
    assert {name: {aid for aid in TRAINING_AIDS if issubclass(config_class(name), aid)} for name in shipped} == shipped
    aid_fields = {f.name for aid in TRAINING_AIDS for f in dataclasses.fields(aid)}
    assert not aid_fields & SHARED and not aid_fields & set(own_settings("sac_curl"))
    # off for a learner without it: accepted and dropped; on: one line naming the learners that have it
    curl = load_config("cpu", {"algorithm": "sac_curl", "demo_episodes": 0, "critic_privileged_state": False})
    assert not hasattr(curl, "demo_episodes")
    assert demonstration_settings(curl) == DemonstrationSettings() and not critic_reads_state(curl)
    with pytest.raises(ValueError, match="has no field 'critic_privileged_state' \\(a setting of sac_drq, "):
        load_config("cpu", {"algorithm": "sac_curl", "critic_privileged_state": True})
    drq = load_config("cpu")
    assert demonstration_settings(drq) is drq and critic_reads_state(drq)
    # listed right after the run setting each names, whatever class declares them
    order, run = field_order(), [f.name for f in dataclasses.fields(RunSettings)]
    for aid in TRAINING_AIDS:
        names = [f.name for f in dataclasses.fields(aid)]
        assert aid.shown_after in run
        start = order.index(aid.shown_after) + 1
        assert list(order[start:start + len(names)]) == names, aid.__name__


def test_the_config_page_gives_each_learner_the_shared_fields_and_exactly_its_own():
    """The docs site's config page (built at each docs build, egosearch.rl.config_page): one section of the
    shared fields, then one per registered learner listing exactly its own, each with its paper value."""
    from egosearch.rl.config_page import config_page

    page = config_page()
    shared = page.split("## Shared by every learner")[1].split("\n## ")[0]
    assert [line.split("`")[1] for line in shared.splitlines() if line.startswith("| `")] == sorted(
        SHARED, key=field_order().index)
    for name in LEARNERS:  # a learner registered later (tests/test_extending.py's toy) has its section too
        section = page.split(f"(`algorithm: {name}`)")[1].split("\n## ")[0]
        assert [line.split("`")[1] for line in section.splitlines() if line.startswith("| `")] == list(
            own_settings(name))
    assert "| `bc_weight_floor` | `0.0` |  |" in page  # the paper's value; the cpu preset leaves it at 0
