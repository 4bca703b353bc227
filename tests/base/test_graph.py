import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from supportless.base.graph import edge_components


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 40).flatmap(lambda n: st.tuples(
    st.just(n), st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)), max_size=60))))
def test_the_labels_are_scipys(graph):
    n, edges = graph
    E = np.array(edges, np.int64).reshape(-1, 2)
    expected = connected_components(coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n)), directed=False)
    count, labels = edge_components(n, E[:, 0], E[:, 1])
    assert count == expected[0]
    np.testing.assert_array_equal(labels, expected[1])


def test_loops_and_lone_nodes():
    # two triangles 0-4-2 and 1-3-5 given backwards, and a lone node 6: numbered by their smallest node
    count, labels = edge_components(7, np.array([4, 2, 0, 5, 3, 1]), np.array([2, 0, 4, 3, 1, 5]))
    assert count == 3
    np.testing.assert_array_equal(labels, [0, 1, 0, 1, 0, 1, 2])
    assert edge_components(3, np.zeros(0, np.int64), np.zeros(0, np.int64))[0] == 3


def test_an_edge_outside_the_nodes_is_refused():
    with pytest.raises(ValueError, match="outside"):
        edge_components(3, np.array([0]), np.array([3]))
    with pytest.raises(ValueError, match="two"):
        edge_components(3, np.array([0, 1]), np.array([1]))
