# temporary forwarder: the road helper moves the film model here
from rain_core.road import WET_FILM_MM, film_depth_mm  # noqa: F401
