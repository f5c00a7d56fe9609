"""``prefetch(array, i)``: ask the CPU to bring row ``i`` of ``array`` into its caches, from a
numba kernel (LLVM's ``llvm.prefetch``, a hint: it never faults and changes no value).

For gathers whose index is known a few iterations early: the z-buffer's rast reads each bin
entry's triangle from a scene array of megabytes, one random row per entry, and stalled on
those loads for a tenth of its time on a real scan (perf, the bunny at 500 x 500).
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic


@intrinsic
def prefetch(typingctx, array, index):
    """Prefetch ``array[index]`` (its first element for a row of a 2-D array) for reading,
    into every cache level."""
    signature = types.void(array, index)

    def codegen(context, builder, sig, args):
        array_type, index_type = sig.args
        data = context.make_array(array_type)(context, builder, args[0])
        where = [context.cast(builder, args[1], index_type, types.intp)]
        where += [context.get_constant(types.intp, 0)] * (array_type.ndim - 1)
        pointer = cgutils.get_item_pointer(context, builder, array_type, data, where,
                                           wraparound=False)
        byte_pointer, i32 = ir.IntType(8).as_pointer(), ir.IntType(32)
        hint = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [byte_pointer, i32, i32, i32]),
            "llvm.prefetch.p0")
        # read (0), keep in every level (locality 3), data cache (1)
        builder.call(hint, [builder.bitcast(pointer, byte_pointer), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()
    return signature, codegen
