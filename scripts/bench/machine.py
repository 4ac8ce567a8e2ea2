"""What the benchmark scripts print about the machine they ran on (imported by them)."""
import os
import platform
import subprocess


def cpu_model() -> str:
    """The processor's model name from /proc/cpuinfo, or the architecture."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.machine()


def load_average() -> str:
    """The 1, 5 and 15 minute load averages, as the kernel gives them."""
    try:
        with open("/proc/loadavg") as fh:
            return " ".join(fh.read().split()[:3])
    except OSError:
        return "unknown"


def rustc_version() -> str:
    return subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()


def cpus() -> str:
    return f"{cpu_model()}, {os.cpu_count()} logical CPUs (shared)"
