"""Training the retargeting network on the synthetic motion world (Aberman et al. 2019, Sec. 4-5).

Each sample draws two (motion, character, view) triples from a split of :mod:`retarget.world` and the
windows of all 8 combinations; the batch is augmented (:mod:`retarget.training.augment`) and the objective of
:mod:`retarget.training.losses` is minimised with AMSGrad. Optional real tracks (OpenPose folders) add a
self-reconstruction term. One checkpoint file (:mod:`retarget.network.checkpoint`) is rewritten atomically after
every epoch and when the time budget ends; ``resume=True`` continues it exactly where it stopped.

Under ``torchrun`` (:mod:`retarget.training.distributed`) every process trains its part of each global batch of
``batch_size`` samples in DistributedDataParallel; rank 0 writes the checkpoint, which resumes under any
number of processes. On CUDA the network runs in bfloat16 autocast (``amp``).

The split interface used here (the motion world provides it)::

    split.num_motions, split.num_characters, split.num_views
    split.views  # yaw of each view bin (degrees); read only with TrainConfig.frontal_share
    split.window(motion, character, view, length=64, offset=0, rng=None) -> [length, 15, 2] float32
    split.window(..., cameras=CameraSpread(...))  # only when TrainConfig.cameras is not the world's

Modules: :mod:`~retarget.training.config` (:class:`TrainConfig`), :mod:`~retarget.training.data` (samples,
real windows, statistics, body scales), :mod:`~retarget.training.step` (batch tensors, the loss of one step,
validation), :mod:`~retarget.training.state` (where a run starts, what its steps share, its checkpoint and
resume state), :mod:`~retarget.training.loop` (the loop: epochs, time budget, the best epoch, the weight average) and
:mod:`~retarget.training.run` (from folders on disk to :func:`~retarget.training.loop.fit`). Import the public names
from those modules.
"""
