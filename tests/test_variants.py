"""Every variant file in ablations/ loads, and a bad one is one clear line."""

import pytest

from egosearch.variants import VariantError, load_variant, variant_names


@pytest.mark.parametrize("name", variant_names())
def test_every_ablation_file_loads_and_its_config_validates(name):
    from egosearch.rl.config import load_config

    variant = load_variant(name)
    assert variant.name == name
    for profile in ("smoke", "cpu", "paper"):  # `egosearch variant check` checks all three
        load_config(profile, variant.config)


def test_bad_variant_files(tmp_path):
    (tmp_path / "typo.yaml").write_text("name: typo\nenv_id: EgoSearch-v1\ntrain_env: {layout: kitchen_living, "
                                        "placement: everywhere}\n")
    with pytest.raises(VariantError, match="env_id"):
        load_variant("typo", tmp_path)
    (tmp_path / "wrongname.yaml").write_text("name: other\nenv_id: EgoSearch-v0\ntrain_env: {layout: kitchen_living, "
                                             "placement: everywhere}\n")
    with pytest.raises(VariantError, match="must equal the file name"):
        load_variant("wrongname", tmp_path)
    with pytest.raises(VariantError, match="allowed: typo, wrongname"):
        load_variant("missing", tmp_path)
