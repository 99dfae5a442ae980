"""Gymnasium environments of rrtdrive (installed as ``rrtdrive.envs``)."""
