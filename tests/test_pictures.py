import numpy as np
import pytest


def test_pictures_command_writes_three_nonblank_pngs(tmp_path):
    imageio = pytest.importorskip("imageio.v3")
    from egosearch.cli import main

    assert main(["pictures", "--layout", "bedroom_bath", "--out-dir", str(tmp_path)]) == 0
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == ["bedroom_bath_placements.png", "bedroom_bath_topdown.png", "bedroom_bath_views.png"]
    for path in tmp_path.glob("*.png"):
        image = imageio.imread(path)
        assert image.shape[0] > 300 and image.shape[1] > 300
        assert np.asarray(image[..., :3], float).std() > 20  # not a blank canvas


def test_cli_bad_input_is_one_line(capsys):
    from egosearch.cli import main

    assert main(["scenarios", "--layout", "garage", "--out", "/tmp/never.csv"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "garage" in err[0] and "kitchen_living" in err[0]
