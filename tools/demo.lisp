;;;; tools/demo.lisp -- load luv-physics and run its default scene (make demo).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(let ((scene (find-symbol "RUN-DEFAULT-SCENE" '#:luv-physics)))
  (if (and scene (fboundp scene))
      (funcall scene)
      (format t "~&luv-physics is loaded (kernel families here: ~S), ~
                 but the page does not define RUN-DEFAULT-SCENE yet.~%"
              (funcall (find-symbol "AVAILABLE-KERNEL-FAMILIES" '#:luv-physics)))))
