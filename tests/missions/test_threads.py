"""Every bearings command pins numeric thread pools to one thread before numpy loads."""

from __future__ import annotations

import subprocess
import sys

from missions.threads import THREAD_POOLS, pin_thread_pools


def test_unset_pools_get_one_thread_and_a_count_the_user_set_is_kept():
    env = {"OPENBLAS_NUM_THREADS": "4", "OMP_NUM_THREADS": " "}
    pinned = pin_thread_pools(env)
    assert env["OPENBLAS_NUM_THREADS"] == "4"
    assert env["OMP_NUM_THREADS"] == env["MKL_NUM_THREADS"] == "1"
    assert pinned == {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def test_the_cli_pins_them_before_any_command_imports_numpy():
    code = ("import sys, os\nfrom missions import cli\nassert 'numpy' not in sys.modules\n"
            "cli.main(['validate', 'square'])\nassert 'numpy' in sys.modules\n"
            f"print(','.join(os.environ[name] for name in {THREAD_POOLS!r}))")
    env = {"PATH": "", "PYTHONPATH": ":".join(sys.path)}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert done.stdout.strip().splitlines()[-1] == "1,1,1"
