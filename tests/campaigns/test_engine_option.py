"""A campaign's engine (`[solver] engine`, `--engine`; issue 43): the CPU lane engine by default, whose specs keep
their hash; the CUDA engine refused before any run on a machine without a GPU, naming the field (CI has none)."""

from pathlib import Path

import pytest

import campaigns
from campaigns.runner.spec import SpecError
from twin.engine.cuda import unavailable

SPECS = Path(__file__).resolve().parents[2] / "campaigns" / "specs"


def _spec(tmp_path: Path, engine: str | None) -> Path:
    path = tmp_path / "engine.toml"
    table = f'\n[solver]\nengine = "{engine}"\n' if engine else ""
    path.write_text(f'extends = "{SPECS / "demo.toml"}"\nname = "engine_check"\n{table}')
    return path


def test_the_cpu_engine_is_the_default_and_leaves_the_spec_hash_alone(tmp_path):
    default = campaigns.load_spec(_spec(tmp_path, None))
    explicit = campaigns.load_spec(_spec(tmp_path, "cpu"))
    assert default.solver.engine == explicit.solver.engine == "cpu"
    assert explicit.spec_hash() == default.spec_hash()
    # so a spec written before the engine existed keeps its hash
    assert "engine" not in default.canonical()["spec"]["solver"]


@pytest.mark.skipif(not unavailable(), reason="this machine has a usable GPU: the refusal is for one without")
def test_the_cuda_engine_without_a_gpu_is_refused_before_any_run_naming_the_field(tmp_path):
    with pytest.raises(SpecError, match="solver.engine: 'cuda' cannot run here"):
        campaigns.load_spec(_spec(tmp_path, "cuda"))
