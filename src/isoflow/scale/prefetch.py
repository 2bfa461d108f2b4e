"""A hint to the processor, for compiled passes that write where they will
soon write again: fetch the cache line of ``arr[i]`` now, for writing.

A pass that scatters its writes over a large array (the shell of a mesh
sets a few voxels in each of millions of cache lines) waits for each line
as it first touches it; naming the lines a little ahead lets those waits
overlap.  The hint changes no value: where the line is not fetched in time,
the write waits as it would have.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.extending import intrinsic


@intrinsic
def prefetch_write(typingctx, arr, i):
    """``llvm.prefetch`` of the address of ``arr[i]`` (a one-dimensional,
    contiguous array), for writing, kept in every cache level.  Callable
    only from compiled code."""
    sig = types.void(arr, types.intp)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, args[0])
        byte = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fn = builder.module.declare_intrinsic(
            "llvm.prefetch", fnty=ir.FunctionType(ir.VoidType(), [byte, i32, i32, i32]))
        address = builder.bitcast(builder.gep(ary.data, [args[1]]), byte)
        # write (1), keep in all levels (3), data rather than instructions (1)
        builder.call(fn, [address, ir.Constant(i32, 1), ir.Constant(i32, 3), ir.Constant(i32, 1)])
        return context.get_dummy_value()

    return sig, codegen
