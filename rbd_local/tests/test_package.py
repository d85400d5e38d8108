import rbd_local


def test_version_matches_pyproject():
    import pathlib

    try:
        import tomllib
    except ModuleNotFoundError:  # Python < 3.11
        import tomli as tomllib

    meta = tomllib.loads((pathlib.Path(__file__).parents[1] / "pyproject.toml").read_text())
    assert rbd_local.__version__ == meta["project"]["version"]
