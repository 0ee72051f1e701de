"""A cheaper kernel launch for the kernels a time step makes every step.

Why: launched from Python, a Taichi 1.7 kernel method of a ``@ti.data_oriented`` object costs
~21 us here before any work is done (measured: an empty serial loop over 100 values; the C++
launch itself is ~1 us). The rest is Taichi's per-call bookkeeping: the template key of
``self`` is rebuilt from ``isinstance`` checks that each go through the class's overridden
``__getattribute__``, the argument list is walked type by type, the compiled kernel is looked up
again. A step makes 13-26 such launches, which was 25-40 % of a 1 000-particle 2D step, and
the implicit viscous solve ~14 per iteration.

:class:`Launcher` makes the first call through Taichi's own path (compiling the kernel), keeps
the compiled kernel, and afterwards only sets the scalar arguments and launches: ~2 us. Its
template arguments (fields a kernel is specialised for) are fixed when it is made, so that
one Launcher is one compiled kernel; ``launcher(obj, name, *templates)`` keeps one per object,
kernel and template values. It applies to kernels whose other arguments are Python scalars and
whose result is nothing or a scalar; any other kernel keeps Taichi's path, as does every kernel
after Taichi's runtime has been re-initialised (``runtime.init``). The launch is asynchronous on
GPUs exactly as Taichi's is; a kernel with a result synchronises to read it.
"""
from __future__ import annotations

from taichi.lang import impl
from taichi.lang.exception import handle_exception_from_cpp
from taichi.lang.kernel_impl import Kernel
from taichi.lang.util import cook_dtype
from taichi.types import primitive_types, template
from taichi.types.utils import is_signed

_REAL = set(primitive_types.real_type_ids)
_INTEGER = set(primitive_types.integer_type_ids)


class Launcher:
    """``Launcher(obj.kernel, *templates)(*scalars)`` launches ``obj.kernel`` as Taichi would,
    faster: ``templates`` are the values of its ``ti.template()`` arguments after ``self``, in
    order, ``scalars`` those of the others."""

    __slots__ = ("bound", "kernel", "owner", "templates", "setters", "result", "prog", "compiled", "t_kernel")
    launches = 0  # fast launches and results read back, in this process (bench throughput counts them)
    results = 0

    def __init__(self, bound, *templates):
        self.bound = bound  # Taichi's own path: the first call and every unsupported one
        self.kernel: Kernel = bound._primal
        self.owner = None if bound._is_staticmethod else bound._kernel_owner
        self.templates = templates
        self.prog = None  # the runtime the cached kernel was compiled for
        self.compiled = self.t_kernel = None
        self.setters = self._setters()
        self.result = self._result()

    def _arguments(self):
        return self.kernel.arguments[0 if self.owner is None else 1:]

    def _setters(self):
        """One 'float' / 'int' / 'uint' per scalar argument; None if any argument is neither a
        scalar nor a template, or the templates given do not match the kernel's."""
        kinds = []
        n_templates = 0
        for argument in self._arguments():
            annotation = argument.annotation
            if isinstance(annotation, template):
                n_templates += 1
            elif id(annotation) in _REAL:
                kinds.append("float")
            elif id(annotation) in _INTEGER:
                kinds.append("int" if is_signed(cook_dtype(annotation)) else "uint")
            else:
                return None
        return tuple(kinds) if n_templates == len(self.templates) else None

    def _result(self):
        """'none', 'float' or 'int'; None for anything else (Taichi's path then)."""
        returns = self.kernel.return_type
        if not returns:
            return "none"
        if len(returns) != 1:
            return None
        if returns[0] in primitive_types.real_types:
            return "float"
        if returns[0] in primitive_types.integer_types:
            return "int"
        return None

    def _full(self, scalars) -> tuple:
        """The kernel's positional arguments after ``self``: templates and scalars in their places."""
        templates, values = iter(self.templates), iter(scalars)
        return tuple(next(templates) if isinstance(a.annotation, template) else next(values)
                     for a in self._arguments())

    def _taichi(self, args):
        """Taichi's own launch: of all the arguments as given where this Launcher does not apply."""
        return self.bound(*(args if self.setters is None else self._full(args)))

    def _capture(self, scalars) -> None:
        """After Taichi's own call: the compiled kernel of these template values."""
        full = self._full(scalars)
        key = self.kernel.ensure_compiled(*(full if self.owner is None else (self.owner,) + full))
        self.t_kernel = self.kernel.compiled_kernels[key]
        prog = impl.get_runtime().prog
        self.compiled = prog.compile_kernel(prog.config(), prog.get_device_caps(), self.t_kernel)
        self.prog = prog

    def __call__(self, *scalars):
        if self.setters is None or self.result is None or self.kernel.has_print:
            return self._taichi(scalars)
        prog = impl.get_runtime().prog
        if prog is not self.prog:  # first call, or Taichi re-initialised since: compile through Taichi
            value = self._taichi(scalars)
            self._capture(scalars)
            return value
        context = self.t_kernel.make_launch_context()
        for index, (kind, value) in enumerate(zip(self.setters, scalars)):
            if kind == "float":
                context.set_arg_float((index,), float(value))
            elif kind == "int":
                context.set_arg_int((index,), int(value))
            else:
                context.set_arg_uint((index,), int(value))
        Launcher.launches += 1
        try:
            prog.launch_kernel(self.compiled, context)
        except Exception as error:  # as Taichi's own launch reports it
            raise handle_exception_from_cpp(error) from None
        if self.result == "none":
            return None
        prog.synchronize()
        Launcher.results += 1
        if self.result == "float":
            return context.get_struct_ret_float((0,))
        return context.get_struct_ret_int((0,))


def launcher(obj, name: str, *templates) -> Launcher:
    """The Launcher of ``obj``'s kernel ``name`` specialised for ``templates``, made once and kept
    on ``obj`` (keyed by the templates' identities: they live as long as ``obj`` does)."""
    cache = obj.__dict__.setdefault("_launchers", {})
    key = (name,) + tuple(id(t) for t in templates)
    found = cache.get(key)
    if found is None:
        found = cache[key] = Launcher(getattr(obj, name), *templates)
    return found
