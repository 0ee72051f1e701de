"""runtime.py: the one place that starts Taichi."""
import subprocess
import sys


def test_arch_gpu_without_a_gpu_runs_on_the_cpu_and_says_so():
    """``arch: gpu`` tries CUDA and Vulkan only: Taichi's own ti.gpu also probes OpenGL, which
    crashed the process on a machine without a GPU or display (segfault, measured). In a child
    process, so that this worker's runtime is left alone."""
    code = ("from taichi_granular import runtime; runtime.init('gpu', 'f32'); "
            "print('on_cpu', runtime._on_cpu); runtime.choose_loops(10); print('serial', runtime.serial_loops)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    on_cpu = "on_cpu True" in done.stdout
    assert ("running on the CPU" in done.stderr) == on_cpu
    assert ("serial True" in done.stdout) == on_cpu  # a fallen-back runtime is a CPU one for the loops
