"""The motion-retargeting network of Aberman et al. 2019 and the motion world it is trained on."""
