"""A GPU for machines without one: CPU tensors that say they live on ``cuda:0``, and a check that
raises where CUDA would raise because a tensor on the CPU meets one on the GPU.

:class:`OnGPU` tensors hold real CPU values (so ``.item()``, ``.tolist()``, ``nonzero``, the
segmentation's dynamic programming and every other data-dependent step run as on a GPU) and report
``device`` ``cuda:0``. :class:`GPUCheck`, a ``TorchFunctionMode``, sees every torch call: it turns
``device=cuda:0`` (and ``.to(cuda)``, ``.cuda()``) into a CPU call whose result is marked
:class:`OnGPU`, marks the result of every call that reads an :class:`OnGPU` tensor, unmarks
``.cpu()`` and ``.to("cpu")``, and raises :class:`DeviceMismatch` where CUDA does:

- a call mixes an on-GPU tensor with a CPU tensor of one or more dimensions (a 0-dim CPU tensor
  is a scalar that CUDA takes anywhere, except in ``cat``/``stack``);
- an on-GPU tensor goes to numpy without ``.cpu()``;
- a CPU ``torch.Generator`` draws on the GPU.

CUDA's own exceptions are kept: indexing a GPU tensor with CPU index tensors or masks (also in
``index_put_``), copying between devices (``copy_``, assignment to a basic slice), and the CPU
lengths of packed sequences.
What it cannot see: what bypasses ``__torch_function__`` (the autograd engine's backward, the C++
inside one op), ``tensor.is_cuda`` (False here), ``torch.cuda`` calls, custom CUDA kernels, and errors
CUDA raises for other reasons (memory, cuDNN, autocast's dtypes, non-determinism).
"""

from __future__ import annotations

from typing import Any

import torch
from torch import nn
from torch.overrides import TorchFunctionMode
from torch.utils import _pytree as pytree

GPU = torch.device("cuda", 0)
_TO_NUMPY = {torch.Tensor.numpy, torch.Tensor.__array__}
_NO_SCALARS = {torch.cat, torch.concat, torch.concatenate, torch.stack, torch.hstack, torch.vstack, torch.dstack}
_INDEXED = {torch.Tensor.__getitem__, torch.Tensor.index_put_, torch.Tensor.index_put, torch.index_put}
# packed sequences: lengths and batch_sizes are CPU tensors by design (argument and output 1)
_CPU_ARGUMENT = {torch._pack_padded_sequence: 1, torch._pad_packed_sequence: 1}
_PACKED_RNN = {torch.lstm, torch.gru, torch.rnn_tanh, torch.rnn_relu}  # with batch_sizes as argument 1
_QUERIES = {torch._has_compatible_shallow_copy_type}  # about tensors, not an op on them
_SHAPE_OF_OTHER = {torch.Tensor.view_as, torch.Tensor.expand_as, torch.Tensor.reshape_as}  # read only its shape


class DeviceMismatch(RuntimeError):
    """What CUDA raises as "Expected all tensors to be on the same device"."""


class OnGPU(torch.Tensor):
    """A CPU tensor that stands for one on :data:`GPU` (its ops are only seen by :class:`GPUCheck`)."""

    __torch_function__ = torch._C._disabled_torch_function_impl
    __module__ = "torch"  # code that accepts numpy or torch tells them apart by it (keyin/envs/segmentation.py)

    @property
    def device(self) -> torch.device:
        return GPU


def on_gpu(value: Any) -> bool:
    return isinstance(value, OnGPU)


def _is_gpu(device: Any) -> bool:
    return device is not None and torch.device(device).type == "cuda"


def _mark(value: Any) -> Any:
    return pytree.tree_map_only(torch.Tensor, lambda t: t if on_gpu(t) else t.as_subclass(OnGPU), value)


def _unmark(value: Any) -> Any:
    return pytree.tree_map_only(torch.Tensor, lambda t: t.as_subclass(torch.Tensor) if on_gpu(t) else t, value)


def _name(func: Any) -> str:
    return getattr(func, "__qualname__", None) or getattr(func, "__name__", None) or repr(func)


class GPUCheck(TorchFunctionMode):
    """Runs torch with :class:`OnGPU` tensors as CUDA would (see module doc)."""

    def __torch_function__(self, func, types, args=(), kwargs=None):
        kwargs = dict(kwargs or {})
        if func in _QUERIES:
            return func(*args, **kwargs)
        if func in _TO_NUMPY:
            if on_gpu(args[0]):
                raise DeviceMismatch(f"can't convert {GPU} device type tensor to numpy ({_name(func)}); .cpu() first")
            return func(*args, **kwargs)
        if func is torch.Tensor.cpu:
            return _unmark(func(*args, **kwargs)).clone() if on_gpu(args[0]) else func(*args, **kwargs)
        if func is torch.Tensor.cuda:
            return args[0] if on_gpu(args[0]) else _mark(args[0].clone())
        if func is torch.Tensor.to:
            return self._to(args[0], args[1:], kwargs)
        if func is torch.Tensor.type_as:
            return self._to(args[0], args[1:], {})
        if func in _SHAPE_OF_OTHER:
            out = func(*args, **kwargs)
            return _mark(out) if on_gpu(args[0]) else out
        device = kwargs.get("device")
        if device is not None:
            kwargs["device"] = "cpu"
        tensors = [leaf for leaf in pytree.tree_leaves((args, kwargs)) if isinstance(leaf, torch.Tensor)]
        gpu = any(on_gpu(t) for t in tensors) or _is_gpu(device)
        if gpu:
            self._check(func, args, kwargs, tensors)
        out = func(*args, **kwargs)
        same = bool(args) and out is args[0]  # in place, or nothing to do: the tensor itself
        if device is not None:
            out = out.clone() if same and on_gpu(out) != _is_gpu(device) else out
            return _mark(out) if _is_gpu(device) else _unmark(out)
        if same:
            return out
        if gpu and func in _CPU_ARGUMENT:
            return (_mark(out[0]), *out[1:])
        return _mark(out) if gpu else out

    @staticmethod
    def _check(func: Any, args: tuple, kwargs: dict, tensors: list[torch.Tensor]) -> None:
        """Raise where a CPU tensor meets a GPU one in ``func``, as CUDA would."""
        generator = kwargs.get("generator")
        if generator is not None and generator.device.type != "cuda":
            raise DeviceMismatch(f"{_name(func)}: expected a 'cuda' device type for generator but found "
                                 f"'{generator.device.type}'")
        if func is torch.Tensor.copy_:  # a copy across devices is allowed
            return
        allowed: list[torch.Tensor] = []
        if func in _INDEXED and on_gpu(args[0]):  # CUDA takes index tensors on the CPU
            allowed = [leaf for leaf in pytree.tree_leaves(args[1]) if isinstance(leaf, torch.Tensor)]
        if func in _CPU_ARGUMENT:
            allowed = [args[_CPU_ARGUMENT[func]]]
        if func in _PACKED_RNN and isinstance(args[1], torch.Tensor):
            allowed = [args[1]]
        if func is torch.Tensor.__setitem__:
            indices = [leaf for leaf in pytree.tree_leaves(args[1]) if isinstance(leaf, torch.Tensor)]
            if not indices:  # a basic slice: a copy_, from any device
                return
            allowed = indices if on_gpu(args[0]) else []
        smallest = 0 if func in _NO_SCALARS else 1
        cpu = [t for t in tensors if not on_gpu(t) and t.dim() >= smallest and not any(t is a for a in allowed)]
        if cpu:
            shapes = ", ".join(str(tuple(t.shape)) for t in cpu)
            raise DeviceMismatch(
                f"Expected all tensors to be on the same device, but found at least two devices, {GPU} and cpu! "
                f"({_name(func)} got CPU tensor(s) of shape {shapes})"
            )

    @staticmethod
    def _to(tensor: torch.Tensor, args: tuple, kwargs: dict) -> torch.Tensor:
        """``Tensor.to``: a copy marked or unmarked where it changes device, else torch's own result."""
        if args and isinstance(args[0], torch.Tensor):
            device, dtype = args[0].device, args[0].dtype
        else:
            options = {key: value for key, value in kwargs.items() if key != "copy"}
            device, dtype, _, _ = torch._C._nn._parse_to(*args, **options)
        moved = torch.Tensor.to(tensor, dtype=dtype or tensor.dtype, copy=bool(kwargs.get("copy")))
        if device is None or _is_gpu(device) == on_gpu(tensor):
            return _mark(moved) if on_gpu(tensor) else moved
        moved = moved.clone() if moved is tensor else moved
        return _mark(moved) if _is_gpu(device) else _unmark(moved)


def to_gpu(module: nn.Module) -> nn.Module:
    """Mark ``module``'s parameters and buffers :class:`OnGPU` (a LightningModule's ``device`` too),
    as ``module.to("cuda")`` would; call inside :class:`GPUCheck`."""
    overwrite = torch.__future__.get_overwrite_module_params_on_conversion()
    torch.__future__.set_overwrite_module_params_on_conversion(True)  # new Parameter objects (LSTMs re-read them)
    try:
        module._apply(lambda t: t if on_gpu(t) else t.as_subclass(OnGPU))
    finally:
        torch.__future__.set_overwrite_module_params_on_conversion(overwrite)
    for part in module.modules():
        if hasattr(part, "_device"):  # Lightning's DeviceDtypeModuleMixin
            part._device = GPU
    return module


def batch_on_gpu(batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """Every tensor of ``batch`` on :data:`GPU`, as the Trainer hands a training or validation step its batch."""
    return {key: value.as_subclass(OnGPU) if isinstance(value, torch.Tensor) else value for key, value in batch.items()}
