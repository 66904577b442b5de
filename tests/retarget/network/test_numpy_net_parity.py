"""The fast formulations inside retarget.network.numpy_net give the numbers of the plain ones they replaced.

The decoder's upsampling convolution is worked out on the low-rate signal in 4-tap windows with small
corrections at the ends; it must be the plain one (nearest x2 upsampling, reflection padding, convolution, here
in float64) and the 5-tap product with dense end weights it replaced (float32), up to float32 rounding. The
columns of a convolution are one copy of a strided view; they must be the concatenated taps bit for bit.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from retarget.network.model import VARIANTS, RetargetNet
from retarget.network.numpy_net import NumpyRetargetNet, _conv, _im2col_weight, _matrix, _UpConv

pytestmark = pytest.mark.usefixtures("one_thread")


def _layer(kernel: int, c_in: int = 24, c_out: int = 20, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.normal(0, 0.3, (c_out, c_in, kernel)).astype(np.float32), rng.normal(0, 1, c_out).astype(np.float32)


def _plain(weight: np.ndarray, bias: np.ndarray, a: np.ndarray) -> np.ndarray:
    """[B, n, Cin] -> [B, 2n, Cout] in float64: upsample, reflect, convolve, one output frame at a time."""
    kernel = weight.shape[-1]
    pad = (kernel - 1) // 2
    u = np.repeat(a.astype(np.float64), 2, axis=1)  # [B, 2n, Cin]
    u = np.concatenate([u[:, pad:0:-1], u, u[:, -2 : -pad - 2 : -1]], axis=1) if pad else u
    w = weight.astype(np.float64)
    return np.stack([np.einsum("bkc,ock->bo", u[:, t : t + kernel], w) for t in range(u.shape[1] - kernel + 1)],
                    axis=1) + bias  # fmt: skip


def _five_taps(weight: np.ndarray, bias: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The decoder layer as it was: one product of 5 low-rate taps for both phases, dense end weights."""
    c_out, c_in, kernel = weight.shape
    pad = (kernel - 1) // 2
    lo = hi = (pad + 1) // 2
    poly = np.zeros((lo + hi + 1, c_in, 2, c_out))
    left, right = np.zeros((pad, c_in, pad, c_out)), np.zeros((pad, c_in, pad, c_out))
    for k in range(kernel):
        w = weight[:, :, k].T
        for phase in (0, 1):
            poly[(phase + k - pad) // 2 + lo, :, phase] += w
        for m in range(pad):
            left[abs(m + k - pad) // 2, :, m] += w
            ahead = m + k - 2 * pad
            right[pad + (ahead if ahead < 0 else -2 - ahead) // 2, :, m] += w
    b, n, _ = a.shape
    padded = np.concatenate([a[:, :1].repeat(lo, 1), a, a[:, -1:].repeat(hi, 1)], axis=1)
    out = _conv(padded, _matrix(poly), None, lo + hi + 1).reshape(b, 2 * n, -1)
    out[:, :pad] = (a[:, :pad].reshape(b, -1) @ _matrix(left)).reshape(b, pad, -1)
    out[:, -pad:] = (a[:, -pad:].reshape(b, -1) @ _matrix(right)).reshape(b, pad, -1)
    return out + bias


def _rounding(reference: np.ndarray) -> float:
    """Room for float32 rounding in sums of a few hundred products of this size."""
    return 2e-6 * float(np.abs(reference).max())


# the plain path for short inputs, else the polyphase one; reflection needs more upsampled frames than the padding
@pytest.mark.parametrize(("kernel", "frames"), [(k, n) for k in (1, 3, 5, 7, 9, 11) for n in (1, 3, 8, 9, 13, 64)
                                                if 2 * n > (k - 1) // 2])  # fmt: skip
def test_decoder_layer_is_the_upsampled_convolution(kernel, frames):
    weight, bias = _layer(kernel, seed=kernel * 100 + frames)
    a = np.random.default_rng(frames).normal(0, 2, (3, frames, weight.shape[1])).astype(np.float32)
    expected = _plain(weight, bias, a)
    got = _UpConv.build(weight, bias)(a)
    assert got.dtype == np.float32 and got.shape == expected.shape
    np.testing.assert_allclose(got, expected, rtol=0, atol=_rounding(expected))


@pytest.mark.parametrize("frames", [9, 16, 128, 257])
def test_decoder_layer_is_the_five_tap_product_it_replaced(frames):
    weight, bias = _layer(7, c_in=128, c_out=64, seed=frames)
    a = np.random.default_rng(frames).normal(0, 1, (2, frames, 128)).astype(np.float32)
    old = _five_taps(weight, bias, a)
    new = _UpConv.build(weight, bias)(a)
    np.testing.assert_allclose(new, old, rtol=0, atol=_rounding(old))
    # and both are the float64 formula's numbers rounded, neither a worse approximation than the other
    exact = _plain(weight, bias, a)
    assert np.abs(new - exact).max() <= 2 * np.abs(old - exact).max() + 1e-7


@pytest.mark.parametrize(("kernel", "stride", "frames"), [(8, 2, 70), (8, 2, 71), (4, 1, 33), (7, 1, 40)])
def test_columns_are_the_concatenated_taps_bit_for_bit(kernel, stride, frames):
    rng = np.random.default_rng(kernel + frames)
    x = rng.normal(size=(2, frames, 30)).astype(np.float32)
    weight = _im2col_weight(rng.normal(size=(16, 30, kernel)).astype(np.float32))
    bias = rng.normal(size=16).astype(np.float32)
    t = (frames - kernel) // stride + 1
    cols = np.concatenate([x[:, k : k + stride * (t - 1) + 1 : stride] for k in range(kernel)], axis=2)
    expected = (cols.reshape(2 * t, -1) @ weight).reshape(2, t, -1) + bias
    for given in (x, np.asfortranarray(x)):  # the same numbers in any memory order
        assert _conv(given, weight, bias, kernel, stride).tobytes() == expected.tobytes()


@pytest.mark.parametrize("kernel", [3, 5, 9])
def test_other_decoder_kernels_match_torch(kernel):
    config = dataclasses.replace(VARIANTS["full"], decoder_kernel=kernel)
    torch.manual_seed(kernel)
    model = RetargetNet(config).eval()
    net = NumpyRetargetNet(config, {k: v.numpy() for k, v in model.state_dict().items()})
    x = torch.randn(2, 30, 64, generator=torch.Generator().manual_seed(kernel))
    with torch.no_grad():
        body, view = model.encode_body(x), model.encode_view(x)
        expected = model.decode(model.encode_motion(x), body, view).numpy()
    np.testing.assert_allclose(net.run(x.numpy(), body.numpy(), view.numpy()), expected, atol=1e-4)
