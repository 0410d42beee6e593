import pytest

from astiop.config import ConfigError, load_settings, to_toml


def test_defaults(tmp_path):
    s = load_settings(env={}, path=tmp_path / "missing.toml")
    assert s.llm.model == "embedded" and s.robot.backend == "sim"
    assert s.robot.max_linear_speed == 0.8 and s.robot.max_angular_speed == 1.0


def test_file_then_env_then_flags(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[llm]\nmodel = "rules"\nthreads = 2\n[sim]\nseed = 7\n')
    env = {"ASTIOP_LLM__THREADS": "1", "ASTIOP_MODEL": "ollama:gemma3:1b"}
    s = load_settings({"llm": {"model": "embedded"}}, env=env, path=path)
    assert s.llm.threads == 1 and s.sim.seed == 7 and s.llm.model == "embedded"
    assert load_settings(env=env, path=path).llm.model == "ollama:gemma3:1b"


@pytest.mark.parametrize(
    "text,needle",
    [
        ("[llm\nmodel = 1", "invalid TOML"),
        ('[llm]\nthreads = "many"\n', "llm.threads"),
        ("[robot]\nbackend = 'turtle'\n", "robot.backend"),
        ("[robot]\nmax_linear_speed = 9.0\n", "robot.max_linear_speed"),
        ("[nonsense]\nx = 1\n", "nonsense"),
    ],
)
def test_malformed_file_names_file_and_key(tmp_path, text, needle):
    path = tmp_path / "c.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_settings(env={}, path=path)
    message = str(info.value)
    assert str(path) in message and needle in message and "\n" not in message


def test_bad_env_is_reported(tmp_path):
    with pytest.raises(ConfigError, match="ASTIOP_.*llm.threads"):
        load_settings(env={"ASTIOP_LLM__THREADS": "zero"}, path=tmp_path / "none.toml")


def test_toml_round_trip(tmp_path):
    s = load_settings({"llm": {"endpoints": ["ollama:a"]}}, env={}, path=tmp_path / "x.toml")
    path = tmp_path / "back.toml"
    path.write_text(to_toml(s))
    assert load_settings(env={}, path=path) == s


def test_variables_nest_split_lists_and_refuse_typos(tmp_path):
    none = tmp_path / "none.toml"
    env = {"ASTIOP_LLM__ENDPOINTS": "ollama:a, openai:b@http://h:1/v1", "ASTIOP_ROBOT": "ros2"}
    s = load_settings(env=env, path=none)
    assert s.llm.endpoints == ["ollama:a", "openai:b@http://h:1/v1"] and s.robot.backend == "ros2"
    for typo in ("ASTIOP_LLM__THREAD", "ASTIOP_SIMULATOR__SEED", "ASTIOP_LLM__MODEL__X"):
        with pytest.raises(ConfigError, match=typo):
            load_settings(env={typo: "1"}, path=none)


def test_settings_alone_read_flags_over_environment_over_file(tmp_path, monkeypatch):
    from astiop.config import Settings

    path = tmp_path / "c.toml"
    path.write_text('[llm]\nmodel = "rules"\nthreads = 2\n')
    monkeypatch.setenv("ASTIOP_CONFIG", str(path))
    monkeypatch.setenv("ASTIOP_LLM__THREADS", "3")
    assert (Settings().llm.model, Settings().llm.threads) == ("rules", 3)
    assert Settings(llm={"threads": 4}).llm.threads == 4
