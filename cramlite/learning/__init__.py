"""Learned ordering strategies (thesis 3.3.4): a GRU network and a CPT+ that see only the
item sequences, and a feed-forward network that also sees the context.

Training needs the `learn` extra (keras 3 on jax's CPU backend, `cpt`); running a trained
RNN or NN needs only numpy (its forward pass is computed from the stored weights), a CPT
model needs `cpt`. Heavy imports happen inside the functions that need them.
"""
