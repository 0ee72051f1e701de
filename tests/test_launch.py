"""launch.py: the fast launch gives what Taichi's own launch gives, and steps aside where it must."""
import numpy as np
import taichi as ti

from taichi_granular.launch import Launcher, launcher


@ti.data_oriented
class Sums:
    def __init__(self, n):
        self.values = ti.field(float, n)
        self.values.from_numpy(np.linspace(0.5, 3.0, n))
        self.total = ti.field(float, ())

    @ti.kernel
    def scale(self, factor: float, first: ti.i32):
        for i in range(first, self.values.shape[0]):
            self.values[i] *= factor

    @ti.kernel
    def sum_from(self, first: ti.i32) -> float:
        result = 0.0
        ti.loop_config(serialize=True)
        for i in range(first, self.values.shape[0]):
            result += self.values[i]
        return result

    @ti.kernel
    def count_above(self, limit: float) -> ti.i32:
        count = 0
        for i in range(self.values.shape[0]):
            if self.values[i] > limit:
                count += 1
        return count

    @ti.kernel
    def add_into(self, target: ti.template(), amount: float):
        for i in range(target.shape[0]):
            target[i] += amount


def test_fast_launch_matches_taichi_arguments_and_results():
    fast, slow = Sums(37), Sums(37)
    for factor, first in [(2.0, 0), (0.5, 10), (3.0, 36), (1.25, 5)]:  # first call compiles, then fast
        launcher(fast, "scale")(factor, first)
        slow.scale(factor, first)
        np.testing.assert_array_equal(fast.values.to_numpy(), slow.values.to_numpy())
    for first in (0, 3, 36):
        assert launcher(fast, "sum_from")(first) == slow.sum_from(first)
    counter = launcher(fast, "count_above")
    assert [counter(x) for x in (0.0, 1.5, 100.0)] == [slow.count_above(x) for x in (0.0, 1.5, 100.0)]
    assert counter(0.0) == 37 and counter(100.0) == 0
    assert isinstance(counter(1.0), int) and isinstance(launcher(fast, "sum_from")(0), float)


def test_fast_path_taken_after_the_first_call_and_cached_per_object():
    sums = Sums(8)
    scale = launcher(sums, "scale")
    assert launcher(sums, "scale") is scale and launcher(Sums(8), "scale") is not scale
    before = Launcher.launches
    scale(2.0, 0)  # through Taichi (compiles and captures)
    scale(2.0, 0)
    scale(2.0, 0)
    assert Launcher.launches - before == 2
    np.testing.assert_allclose(sums.values.to_numpy(), 8.0 * np.linspace(0.5, 3.0, 8))


def test_template_arguments_fixed_per_launcher_or_taichis_path():
    sums, other = Sums(5), Sums(5)
    add = launcher(sums, "add_into", sums.values)  # specialised for sums.values
    assert launcher(sums, "add_into", other.values) is not add
    before = Launcher.launches
    for _ in range(3):
        add(1.0)
    launcher(sums, "add_into", other.values)(0.5)
    launcher(sums, "add_into", other.values)(0.5)
    assert Launcher.launches == before + 3  # the first call of each through Taichi
    np.testing.assert_allclose(sums.values.to_numpy(), np.linspace(0.5, 3.0, 5) + 3.0)
    np.testing.assert_allclose(other.values.to_numpy(), np.linspace(0.5, 3.0, 5) + 1.0)
    unbound = launcher(sums, "add_into")  # templates not given: every call through Taichi, as given
    assert unbound.setters is None
    before = Launcher.launches
    unbound(sums.values, 1.0)
    unbound(sums.values, 1.0)
    assert Launcher.launches == before
    np.testing.assert_allclose(sums.values.to_numpy(), np.linspace(0.5, 3.0, 5) + 5.0)


def test_a_new_runtime_is_compiled_for_again():
    sums = Sums(6)
    total = launcher(sums, "sum_from")
    expected = float(np.linspace(0.5, 3.0, 6).sum())
    assert total(0) == expected
    total.prog = object()  # as after runtime.init re-initialised Taichi: not the current program
    before = Launcher.launches
    assert total(0) == expected  # through Taichi again, captured anew
    assert Launcher.launches == before
    assert total(0) == expected and Launcher.launches == before + 1
