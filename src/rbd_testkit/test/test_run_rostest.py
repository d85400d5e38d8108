"""run_rostest: unittest methods in the order of the seed, the seed printed, results as rostest gives them."""

import subprocess
import sys
import textwrap

from rbd_testkit.ros import shuffled_order

SCRIPT = textwrap.dedent("""
    import sys, unittest
    from rbd_testkit.ros import run_rostest

    ran = []

    class Case(unittest.TestCase):
        pass

    for name in %r:
        setattr(Case, name, lambda self, name=name: ran.append(name))

    try:
        run_rostest("rbd_testkit", "order", Case)
    finally:
        print("RAN " + " ".join(ran))
""")
NAMES = ["test_%s" % c for c in "abcdefgh"]


def run(seed):
    out = subprocess.run([sys.executable, "-c", SCRIPT % NAMES, "--text"], stdout=subprocess.PIPE,  # noqa: UP022
                         stderr=subprocess.PIPE, universal_newlines=True, env=_env(seed), timeout=60)
    assert out.returncode == 0, out.stdout + out.stderr
    ran = [line for line in out.stdout.splitlines() if line.startswith("RAN ")][-1].split()[1:]
    return ran, out.stderr


def _env(seed):
    import os

    return dict(os.environ, RBD_TEST_SEED=str(seed))


def test_shuffled_order_depends_on_the_seed_and_not_on_the_other_names():
    assert shuffled_order(NAMES, 1) == shuffled_order(list(reversed(NAMES)), 1)
    assert sorted(shuffled_order(NAMES, 1)) == NAMES
    assert len({tuple(shuffled_order(NAMES, seed)) for seed in range(1, 6)}) > 1
    with_extra = shuffled_order(NAMES + ["test_z"], 1)
    assert [n for n in with_extra if n != "test_z"] == shuffled_order(NAMES, 1)


def test_methods_run_in_the_seed_order_and_the_seed_is_printed():
    seeds = [seed for seed in range(1, 50) if shuffled_order(NAMES, seed) != sorted(NAMES)][:2]
    for seed in seeds:
        ran, err = run(seed)
        assert ran == shuffled_order(NAMES, seed)
        assert "RBD_TEST_SEED=%d" % seed in err
