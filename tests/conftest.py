from pathlib import Path

import pytest
from hypothesis import settings

ROOT = Path(__file__).resolve().parent.parent

# Deterministic property tests: the same examples on every run and machine.
settings.register_profile("default", derandomize=True, deadline=None, max_examples=150)
settings.load_profile("default")


@pytest.fixture(scope="session")
def learned_skill():
    """The skill learned from the bundled three-region demonstrations (about 1 s to fit) and
    the resampled demonstrations it was learned from."""
    from stl_lfd.hsmm import learn_from_folder

    return learn_from_folder(ROOT / "demos" / "three_regions", 6)


@pytest.fixture(scope="session")
def learned_model(learned_skill):
    return learned_skill[0]


@pytest.fixture(scope="session")
def learned_model_file(learned_model, tmp_path_factory):
    from stl_lfd.hsmm import save_model

    path = tmp_path_factory.mktemp("model") / "three_regions.npz"
    save_model(learned_model, path)
    return path


def pytest_collection_modifyitems(items):
    """The longest tests (`heavy`) first, then the other end-to-end ones (`slow`), then the
    rest, each group in its own order: handed out one at a time (`--dist loadgroup`; the
    examples of each documentation page go together, first), the two workers start on the
    long tests and finish together on short ones."""
    items.sort(key=lambda item: (item.get_closest_marker("heavy") is None, item.get_closest_marker("slow") is None))
