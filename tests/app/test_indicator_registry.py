"""The one registry of chaos indicators (explorer.kernels.indicator_table) drives every layer: the
Indicators attributes, the names a scene accepts, the sweep's arrays, the store's datasets and
dtypes, the chaos raster's colour scales and the lines of ``explorer lyapunov``; each value is
read from the column the registry names."""
import json
from pathlib import Path

import numpy as np
import pytest

from explorer import model
from explorer.analysis import lyapunov, sweep
from explorer.app import chaos_raster, cli
from explorer.io import scene, store
from explorer.io.store import format as store_format
from explorer.kernels import indicator_table as table

NAMES = [i.name for i in table.INDICATORS]
DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_the_registry_names_each_indicator_once_in_a_column_of_its_row():
    assert len(set(NAMES)) == len(NAMES) > 0
    places = [(i.row, i.column) for i in table.INDICATORS]
    assert len(set(places)) == len(places)
    for i in table.INDICATORS:
        if i.row == table.RESULT:   # not the time nor MEGNO's Y
            assert 0 <= i.column < table.N_RES and i.column not in (table.RES_T, table.RES_Y)
        elif i.row == table.EXTRA:  # not the early-classification code
            assert 0 <= i.column < table.N_EXT and i.column != table.EXT_EARLY
        else:                       # of the section map's returns: not of the tangent loops, asked for only
            assert i.row == table.ORBIT and not i.tangent and not i.default and not i.in_history
    # the tangent loops compute every indicator but those of the orbit's returns
    assert lyapunov.INDICATOR_NAMES == table.TANGENT_NAMES == tuple(n for n in NAMES if table.BY_NAME[n].tangent)
    assert set(lyapunov.DEFAULT_INDICATORS) <= set(table.TANGENT_NAMES)
    assert "frequency_diffusion" in NAMES and "frequency_diffusion" not in lyapunov.INDICATOR_NAMES


@pytest.mark.parametrize("name", NAMES)
def test_every_layer_reads_the_registry(name):
    ind = table.BY_NAME[name]
    assert name in scene.LYAPUNOV_INDICATORS
    assert name in sweep.INDICATOR_ARRAYS
    assert name in store.INDICATOR_DATASETS and name in store.OPTIONAL_DATASETS
    assert store_format._OPTIONAL_PER_ORBIT[name] == ((), np.dtype(ind.dtype))
    style = chaos_raster.STYLES[name]      # how it is drawn: presentation, in the app
    assert chaos_raster.SCALES[name] == (style.label, style.log, style.vmin, style.vmax)
    assert set(chaos_raster.STYLES) == set(NAMES)
    assert name in (DOCS / "commands" / "lyapunov.md").read_text()


def test_indicators_are_read_from_the_registry_columns_and_the_command_prints_each(capsys):
    prm = model.FIGURE4.with_(mu=1.0)
    y0 = model.section_state(prm, [-0.2, 0.3], [0.1, 0.0], model.FIGURE4_H)
    r = lyapunov.indicators(prm, states=y0, tmax=20.0, history=3, which=lyapunov.available("taylor"))
    for i in table.TANGENT:
        values = getattr(r, i.name)
        assert values is r.values[i.name] and values.shape == (2,) and np.isfinite(values).all()
        if i.in_history:   # the last history row is the result row at T
            np.testing.assert_array_equal(r.history[:, -1, i.column], values)
    with pytest.raises(AttributeError):
        r.not_an_indicator  # noqa: B018
    assert cli.main(["lyapunov", "--p1", "-0.2", "--p2", "0.1", "--mu", "1", "--tmax", "20", "--json"]) == 0
    doc = json.loads(capsys.readouterr()[0])
    tangent = list(table.TANGENT_NAMES)   # the command's one orbit has no centre: no frequency diffusion
    assert all(isinstance(doc[name], float) for name in tangent) and "frequency_diffusion" not in doc
    assert cli.main(["lyapunov", "--p1", "-0.2", "--p2", "0.1", "--mu", "1", "--tmax", "20"]) == 0
    lines = capsys.readouterr()[0].splitlines()
    assert [line.split()[0] for line in lines[1:1 + len(tangent)]] == tangent
    history = [i.name for i in table.INDICATORS if i.in_history]
    assert f"history: t, {', '.join(history)}" in lines
