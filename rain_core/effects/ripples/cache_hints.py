"""``prefetch(a, i)``: a hint, inside a compiled kernel, that a[i] (a 1-D array) is about to be read and written,
so the cache line is fetched while the kernel works on something else (LLVM's llvm.prefetch: no load, no fault,
no effect on any value). Called from plain Python (a kernel's twin, or Numba missing) it does nothing.

The bump deposit needs it: its adds land on cells scattered over the 2 MB levels, which the rest of the frame
has evicted, and each bump's cosines are too long for the CPU to reach the next bump's cells on its own.
"""

from __future__ import annotations

from rain_core import jit


def prefetch(a, i) -> None:
    """No-op in Python; in a kernel, the cache line of a[i] is fetched for writing (see the module docstring)."""


if jit.AVAILABLE:
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic, overload

    @intrinsic
    def _llvm_prefetch(typingctx, a, i):
        if not (isinstance(a, types.Array) and a.ndim == 1 and isinstance(i, types.Integer)):
            return None

        def codegen(context, builder, signature, args):
            aryty = signature.args[0]
            ary = context.make_array(aryty)(context, builder, args[0])
            ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [args[1]], wraparound=False)
            byte_ptr = ir.IntType(8).as_pointer()
            i32 = ir.IntType(32)
            # The intrinsic is overloaded on the pointer type: "p0" with opaque pointers, "p0i8" before them.
            name = "llvm.prefetch.p0" if str(byte_ptr) == "ptr" else "llvm.prefetch.p0i8"
            fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(),
                                                                                [byte_ptr, i32, i32, i32]), name)
            # rw = 1 (for a write), locality = 3 (keep in every cache level), cache type = 1 (data)
            builder.call(fn, [builder.bitcast(ptr, byte_ptr), i32(1), i32(3), i32(1)])
            return context.get_dummy_value()

        return types.void(a, i), codegen

    @overload(prefetch)
    def _prefetch_compiled(a, i):
        def impl(a, i):
            _llvm_prefetch(a, i)

        return impl
