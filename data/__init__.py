"""Shipped human table-setting sequences (BSD-3, see human_sequences/), installed as the
package data `cramlite.data`."""
