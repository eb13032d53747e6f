"""Fuzz: field values. Every text a person can type or paste, and every value a file or a
request can carry, gets a value in range or one clear line; never a traceback.

The generator is seeded, so every run tries the same inputs; the other fuzz suites
(`test_fuzz_protocol`, `test_fuzz_storage`) draw their values from it too.
"""

from __future__ import annotations

import argparse
import math
import random
import string
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from tui_gym.algorithms import ALGORITHMS, ALL_PARAMS, QLearning
from tui_gym.cli import build_parser
from tui_gym.cli.flags import HP_FLAGS, game_kwargs
from tui_gym.cli.flags import hyperparameters as _hyperparameters
from tui_gym.cli.output import CliError
from tui_gym.core.params import Param, ParamError
from tui_gym.core.wrappers import CATALOG, parse_wrapper_spec
from tui_gym.games import GAMES, game_for

SEED = 9
CASES = 400

# Digits of other scripts, super- and subscripts, fractions, numerals: Python reads some as digits.
UNICODE_DIGITS = "٠١٢٣٤٥٦٧٨٩۰۱۲۳४५६७८९০১２３²³¹⁰₀₁½Ⅻⅷ𝟙𝟚"
SPACES = [" ", "\t", "\u00a0", "\u2003", "\u3000", ""]
INTERNALS = ("invalid literal", "could not convert", "Exceeds the limit", "OverflowError",
             "Traceback", "int too large", "object of type")


def nasty_text(rng: random.Random) -> str:
    """Text a person might type or paste into a number field, or a file might hold."""
    kind = rng.randrange(14)
    if kind == 0:
        return str(rng.randint(-10**6, 10**6))
    if kind == 1:
        return repr(rng.uniform(-1e3, 1e3))
    if kind == 2:
        digits = rng.choice([308, 309, 310, 400, 4300, 4301, 6000])
        return rng.choice(["", "-", "+"]) + "1" + "0" * (digits - 1)
    if kind == 3:
        return rng.choice(["inf", "-inf", "+inf", "Infinity", "-INFINITY", "nan", "NaN", "-nan",
                           "infinit", "in f", "∞", "-∞"])
    if kind == 4:
        mantissa = rng.choice(["1", "-2.5", ".5", "5.", "0", "9" * 20])
        return f"{mantissa}{rng.choice('eE')}{rng.choice([-400, -308, 0, 308, 309, 400, 99999])}"
    if kind == 5:
        return "".join(rng.choice(UNICODE_DIGITS) for _ in range(rng.randint(1, 4)))
    if kind == 6:
        return str(rng.randint(0, 99)) + rng.choice(UNICODE_DIGITS) + rng.choice(["", "0", ".5"])
    if kind == 7:
        return rng.choice(["1_000", "1__0", "_1", "1_", "1_0.5_0", "1_e5", "0_0", "1e1_0"])
    if kind == 8:
        return rng.choice(["0x10", "0o7", "0b1", "1j", "1+2j", "0X1p3", "1/2", "2,5", "1.2.3"])
    if kind == 9:
        number = rng.choice(["5", "0.25", "-1", "1e2"])
        return rng.choice(SPACES) + number + rng.choice(SPACES)
    if kind == 10:
        return "".join(rng.choice(string.printable) for _ in range(rng.randint(0, 12)))
    if kind == 11:
        return "".join(chr(rng.randrange(0x110000)) for _ in range(rng.randint(1, 6)))
    if kind == 12:
        return rng.choice(["", " ", "\0", "--1", "+-1", "1-", "1e", "e1", ".", "-", "+", "00",
                           "-0", "007", "1" * 5000 + "x"])
    return rng.choice(["true", "False", "yes", "off", "2", "0", "1", "maybe"])


def nasty_value(rng: random.Random, depth: int = 0) -> Any:
    """A value a JSON file or request might hold where a number or a name belongs."""
    kind = rng.randrange(13 if depth < 3 else 8)
    if kind == 0:
        return rng.choice([-1, 1]) * 10 ** rng.randint(0, 400)
    if kind == 1:
        return rng.randint(-5, 5)
    if kind == 2:
        return rng.choice([math.inf, -math.inf, math.nan, 1e308, -0.0, 5e-324, 0.5, 2.5])
    if kind == 3:
        return rng.choice([True, False])
    if kind == 4:
        return None
    if kind == 5:
        return nasty_text(rng)
    if kind == 6:
        return rng.choice([2**63, 2**64, -(2**63) - 1, 2**31, 10**18])
    if kind == 7:
        return "x" * rng.choice([0, 100, 10_000])
    if kind == 8:
        return [nasty_value(rng, depth + 1) for _ in range(rng.randint(0, 3))]
    if kind == 9:
        return {nasty_text(rng): nasty_value(rng, depth + 1) for _ in range(rng.randint(0, 3))}
    if kind == 10:
        value: Any = 0
        for _ in range(rng.choice([10, 50, 200])):
            value = [value]
        return value
    if kind == 11:
        return [0] * 1000
    return rng.choice(["TimeLimit", "stick", "hit", "right", "\ud800", "١"])


def all_params() -> list[Param]:
    """Every numeric or yes/no field a person or a file fills in, each once."""
    params = [p for spec in CATALOG.values() for p in spec.params]
    params += [p for game in GAMES for p in game.params]
    params += [p for learner in ALGORITHMS for p in learner.params if isinstance(p, Param)]
    unique: dict[tuple[str, str], Param] = {}
    for param in params:
        unique.setdefault((param.label, param.describe_range()), param)
    return list(unique.values())


def inputs(seed: int, count: int) -> Iterator[Any]:
    rng = random.Random(seed)
    for i in range(count):
        yield nasty_text(rng) if i % 3 else nasty_value(rng)
    yield from (np.int64(7), np.float32("nan"), np.bool_(True), np.float64(1e300), 10**5000)


def check_one_line(message: str, *labels: str) -> None:
    assert "\n" not in message and message.strip() == message, message
    assert len(message) < 260, message
    for internal in INTERNALS:
        assert internal not in message, message
    if labels:
        assert any(label in message for label in labels), message


@pytest.mark.parametrize(
    "param", all_params(), ids=lambda p: f"{p.label} {p.describe_range()}"
)
def test_every_field_answers_every_value(param: Param) -> None:
    for raw in inputs(SEED, CASES):
        try:
            value = param.parse(raw)
        except ParamError as exc:
            message = str(exc)
            check_one_line(message)
            assert message.startswith(f"{param.label} ")
            assert ("is out of range" in message) == exc.out_of_range
            assert exc.out_of_range or "must be" in message
            continue
        if param.kind is bool:
            assert isinstance(value, bool)
            continue
        assert type(value) is param.kind, (raw, value)
        assert math.isfinite(value)
        assert param.minimum is None or value >= param.minimum
        assert param.maximum is None or value <= param.maximum
        if isinstance(raw, str):
            # Only ASCII digits are digits; surrounding whitespace may be any.
            assert raw.strip().isascii(), raw


def test_out_of_range_is_told_apart_from_not_a_number() -> None:
    factor = CATALOG["ScaleReward"].param("factor")
    steps = CATALOG["TimeLimit"].param("max_episode_steps")
    for raw in ("1" + "0" * 309, "-1" + "0" * 5000, "1e400", "-inf", "101", 1e308, 10**400):
        with pytest.raises(ParamError) as caught:
            factor.parse(raw)
        assert caught.value.out_of_range, raw
    for raw in ("١", "²", "abc", "nan", "0x10", "", [1], None, True):
        with pytest.raises(ParamError) as caught:
            factor.parse(raw)
        assert not caught.value.out_of_range, raw
    with pytest.raises(ParamError, match=r"must be an integer in \[1, 100000\], got '2.5'"):
        steps.parse("2.5")
    assert steps.parse(" 1_000 ") == 1000 and steps.parse("1e3") == 1000


def test_the_app_fields_answer_every_value() -> None:
    from tui_gym.ui.widgets.hyperparameter_form import FieldValidator, field_error

    texts = [t for t in inputs(SEED + 1, CASES) if isinstance(t, str)]
    for field in (p for p in ALL_PARAMS if isinstance(p, Param) and p.kind is not bool):
        for text in texts:
            problem = field_error(field, text)
            if problem is not None:
                check_one_line(problem)
                if isinstance(read_as_number(text), float | int):
                    assert "is not a number" not in problem or math.isnan(read_as_number(text))
    for param in (p for p in all_params() if p.kind is not bool):  # the side panel's fields
        validator = FieldValidator(param)
        for text in texts:
            result = validator.validate(text)
            for description in result.failure_descriptions:
                check_one_line(description)
            try:
                param.parse(text)
            except ParamError:
                assert not result.is_valid, text
            else:
                assert result.is_valid, text


def read_as_number(text: str) -> float | int | None:
    from tui_gym.core.params import read_number

    return read_number(text)


def test_wrapper_specs_answer_every_value() -> None:
    rng = random.Random(SEED + 2)
    for _ in range(CASES):
        spec = rng.choice(list(CATALOG.values()))
        if not spec.params:
            continue
        param = rng.choice(spec.params)
        text = f"{spec.name}:{param.name}={nasty_text(rng).replace(',', '')}"
        try:
            parse_wrapper_spec(text)
        except ValueError as exc:
            check_one_line(str(exc))


def test_the_command_line_answers_every_value(capsys: pytest.CaptureFixture[str]) -> None:
    rng = random.Random(SEED + 3)
    parser = build_parser()
    base = QLearning
    for _ in range(CASES // 2):
        text = nasty_text(rng).replace("\0", "")
        flag = rng.choice(["--episodes", "--learning-rate", "--discount", "--epsilon-start",
                           "--seed", "--eval-episodes", "--target-gap", "--size"])
        try:
            args = parser.parse_args(["train", "gridworld", f"{flag}={text}"])
        except SystemExit as exit_:
            assert exit_.code == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1, err
            check_one_line(err.strip(), flag)
            continue
        try:
            _hyperparameters(args, base)
            if flag == "--size":
                game_kwargs(args, game_for("gridworld"))
        except CliError as exc:
            check_one_line(str(exc), flag)
    assert set(HP_FLAGS) == {f.name for f in ALL_PARAMS}
    assert isinstance(parser, argparse.ArgumentParser)


def test_digits_of_another_script_are_refused_saying_which_to_type() -> None:
    steps = Param("max_episode_steps", int, 100, 1, 10_000, owner="TimeLimit")
    with pytest.raises(ParamError) as refused:
        steps.parse("١٢")
    assert str(refused.value) == ("TimeLimit.max_episode_steps must be an integer in "
                                  "[1, 10000], got '١٢' (digits 0-9 only)")
