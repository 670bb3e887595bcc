/* placeholder: being written */ typedef int xyl__placeholder_turtle;
