"""``mlsgalerkin kernels``: the kernel table on the command line."""

from __future__ import annotations

import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.kernels import KERNELS


def test_kernels_lists_every_kernel(capsys):
    assert main(["kernels"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    for name, k in KERNELS.items():
        row = [ln for ln in lines if ln.split() and ln.split()[0] == name]
        assert len(row) == 1, name
        fields = row[0].split()
        assert float(fields[1]) == k.support
        for d in (1, 2, 3):
            assert float(fields[1 + d]) == pytest.approx(k.alpha[d - 1], abs=5e-6)
        assert fields[5] == ("yes" if k.nonnegative else "no")
    assert "alpha_d / h^d * f(r/h)" in out


def test_unknown_command_exits_with_usage(capsys):
    with pytest.raises(SystemExit) as info:
        main(["no-such-command"])
    assert info.value.code == 2
    assert "usage: mlsgalerkin" in capsys.readouterr().err
