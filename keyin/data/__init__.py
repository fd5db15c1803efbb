"""Datasets: the Brownian generator, the HDF5 format and the LightningDataModules."""
