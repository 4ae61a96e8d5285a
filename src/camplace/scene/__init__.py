"""camplace.scene.build."""
