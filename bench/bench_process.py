"""What the offline bench scripts share: the build's plsa and one process's cost read from the kernel."""
import os
import subprocess
import tempfile
import time


def default_build():
    """The build directory beside bench/."""
    return os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "build")


def plsa_exe(build, who):
    """The build's plsa; exits naming `who` when it is not built."""
    exe = os.path.join(build, "apps", "plsa")
    if not os.access(exe, os.X_OK):
        raise SystemExit(f"{who}: no {exe}; build first (scripts/plsa-dev setup)")
    return exe


def measured(cmd, who):
    """(peak resident KB, CPU seconds, wall seconds) of one process from wait4's rusage (user + system, every
    thread); its standard output discarded, its failure fatal with its standard error."""
    with tempfile.TemporaryFile("w+") as err:
        start = time.monotonic()
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.monotonic() - start
        code = os.waitstatus_to_exitcode(status)
        if code != 0:
            err.seek(0)
            raise SystemExit(f"{who}: {' '.join(cmd)} exited with {code}:\n{err.read()}")
    return usage.ru_maxrss, usage.ru_utime + usage.ru_stime, wall
